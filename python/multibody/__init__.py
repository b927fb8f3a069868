"""Equations of motion of multibody systems, derived symbolically and run at once.

A model (a RON file, or its text) is derived and compiled in-process when it is loaded: a
20-link chain in about a third of a second, with no Rust toolchain on the machine. Then:

>>> import multibody
>>> m = multibody.load("three_body")            # a built-in model, or a path to a .ron file
>>> m.formulations
['lagrange', 'maggi', 'kane', 'reduced_volterra']
>>> x0, momenta = m.initial_state("kane")
>>> m.rhs(0.0, x0, "kane").shape == x0.shape
True

`Model.simulate` integrates one formulation (a pandas DataFrame when pandas is installed),
`multibody.ensemble` runs many members on every core with the GIL released,
`multibody.distributed.ensemble` spreads one over a Dask cluster, and `Model.animate` writes a
self-contained HTML page that plays the motion in 3-D; `multibody.plot(run)` draws a run with
matplotlib.
"""

from __future__ import annotations

import functools
import html as _html
import os as _os
import stat as _stat
import tempfile as _tempfile
import warnings as _warnings
from collections.abc import Mapping
from typing import NamedTuple, Optional

import numpy as np

from . import _multibody
from ._multibody import METHODS, InternalError, ModelError, SimulationError, built_in
from .plotting import plot

__all__ = [
    "Model",
    "Animation",
    "ModelError",
    "SimulationError",
    "InternalError",
    "Trajectory",
    "Linear",
    "load",
    "loads",
    "ensemble",
    "built_in",
    "pendulum_on_cart",
    "plot",
    "floating_chain",
    "METHODS",
]


def load(path, base=None, gravity=None, limits=None) -> "Model":
    """The model in the RON or URDF file at ``path`` (a str or a path), or the built-in model of
    that name (``multibody.built_in()`` lists them). A URDF robot's base is ``"fixed"`` (the
    default) or ``"floating"``, its ``gravity`` three numbers (default ``(0, 0, -9.81)``), its
    joint ``limits`` ``"report"`` (default), ``"record"`` or ``"stop"``. Raises ``ModelError``
    with the file, the line and column, the place in the model and the fix."""
    return Model(_multibody.load(path, base, None if gravity is None else [float(g) for g in gravity], limits))


def loads(text: str, name: str = "<string>") -> "Model":
    """The model in the RON text ``text``; ``name`` is what its errors call the file."""
    return Model(_multibody.loads(text, name))


@functools.lru_cache(maxsize=16)
def _restore(file: str, text: str) -> "Model":
    """The model a pickle carries, derived once per process for each text."""
    return loads(text, name=file)


def pendulum_on_cart(n: int) -> "Model":
    """SymPy's ``n_link_pendulum_on_cart(n)``: a cart (``q0``, ignorable) carrying n point
    masses on massless links at absolute angles ``q1..qn``, gravity along -y."""
    return loads(_multibody._example_text("pendulum_on_cart", n), name=f"pendulum_on_cart_{n}")


def floating_chain(n: int) -> "Model":
    """n rigid links on revolute joints alternating about z and y, on a free-floating base (its
    position ignorable), no gravity: the spatial chain of the benchmarks."""
    return loads(_multibody._example_text("floating_chain", n), name=f"floating_chain_{n}")


class Linear(NamedTuple):
    """The linear model ``x' = A x + B u`` about an operating point, and A's eigenvalues (the
    zeros of cyclic coordinates left out)."""

    A: np.ndarray
    B: np.ndarray
    eigenvalues: np.ndarray


class Trajectory(Mapping):
    """A run's table without pandas: column name -> 1-D array (``t``, each coordinate, each
    rate ``q'``, ``state:...``, the energy and its error, ``momentum:...``, the constraint
    residuals), with the events (name, time, coordinates) and where it came from."""

    def __init__(self, columns, table, events, model, formulation, params, units=None):
        self.columns = list(columns)
        self._table = table
        self.events = list(events)
        self.model = model
        self.formulation = formulation
        self.params = dict(params)
        self.units = dict(units or {})

    def __getitem__(self, name):
        try:
            return self._table[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(name) from None

    def __iter__(self):
        return iter(self.columns)

    def __len__(self):
        return len(self.columns)

    def plot(self, coordinates=None, *, title=None):
        """The run drawn with matplotlib (``multibody.plot``): the coordinates, the invariants'
        errors on logarithmic axes and the conserved momenta; returns the ``Figure``."""
        return plot(self, coordinates, title=title)

    @property
    def t(self) -> np.ndarray:
        return self["t"]

    def to_pandas(self):
        """The same table as a pandas DataFrame (``attrs`` hold the model, the formulation, the
        events, the parameters and the units)."""
        import pandas as pd

        frame = pd.DataFrame(self._table, columns=self.columns)
        frame.attrs.update(model=self.model, formulation=self.formulation, events=self.events, params=self.params, units=self.units)
        return frame

    def __repr__(self):
        return f"<multibody.Trajectory {self.model} {self.formulation}: {self._table.shape[0]} rows, columns {self.columns}>"


def _has_pandas() -> bool:
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


class Model:
    """A model, derived and ready to run (``multibody.load``, ``multibody.loads``).

    Values are given by name (a dict) or in the model's order (a sequence or an array):
    ``params`` over the model's parameters (``Model.params`` holds the defaults), ``q`` and
    ``qdot`` over its coordinates (the file's initial values where not given). A formulation is
    named ``lagrange``, ``maggi``, ``kane`` or ``reduced_volterra`` (``reduced`` too); without
    one, the reduced method where the model has it, else Kane's.
    """

    def __init__(self, native):
        self._native = native
        for line in native.warnings:
            _warnings.warn(f"{native.name}: {line}", stacklevel=3)

    # What the model is.
    name = property(lambda self: self._native.name, doc="The model's name.")
    file = property(lambda self: self._native.file, doc="The file it came from.")
    text = property(lambda self: self._native.text, doc="Its RON text.")
    coordinates = property(lambda self: self._native.coordinates, doc="The generalized coordinates, in order.")
    formulations = property(lambda self: self._native.formulations, doc="The formulations it has.")
    params = property(lambda self: self._native.params, doc="The parameters and their defaults (a dict in order).")
    units = property(lambda self: dict(self._native.units), doc="The units the file gives its coordinates and parameters (`units`).")
    ignorable = property(lambda self: self._native.ignorable, doc="The ignorable coordinates.")
    initial = property(lambda self: self._native.initial, doc="The file's initial (q, qdot).")
    run = property(lambda self: self._native.run, doc="The file's run (t_start, t_end, dt_out), or None.")

    def state_names(self, formulation: Optional[str] = None) -> list:
        """The state of ``formulation``, by name, in order."""
        return self._native.state_names(formulation)

    def inspect(self, latex: bool = False) -> str:
        """What is derived (T, M, N, Q, the constraints, Definition 1, the reduced method's
        matrices), as text or LaTeX."""
        return self._native.inspect(latex)

    def _repr_latex_(self) -> str:
        """The derivation for a notebook: each block of equations as display math, the text
        between them as text."""
        return notebook_latex(self._native.inspect(True))

    def __repr__(self):
        return repr(self._native)

    def _repr_html_(self) -> str:
        """A notebook's summary of the model: a table of its coordinates (ignorable ones
        marked), parameters and formulations (its equations are ``_repr_latex_``)."""
        e = _html.escape
        ignorable = set(self.ignorable)
        rows = [
            ("model", e(self.name)),
            ("file", e(self.file)),
            ("coordinates", ", ".join(f"<b>{e(c)}</b> (ignorable)" if c in ignorable else e(c) for c in self.coordinates)),
            ("parameters", ", ".join(f"{e(k)} = {v:g}" for k, v in self.params.items())),
            ("formulations", ", ".join(e(f) for f in self.formulations)),
        ]
        body = "".join(f"<tr><th style='text-align:left'>{k}</th><td style='text-align:left'>{v}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>"

    def __reduce__(self):
        # As its text: a worker derives it once per process (`_restore` keeps it).
        return (_restore, (self._native.file, self._native.text))

    def initial_state(self, formulation=None, q=None, qdot=None, params=None):
        """``(x, momenta)``: the state of ``formulation`` at ``q``, ``qdot``, and the conserved
        momenta of the ignorable coordinates there (``rhs`` of the reduced method needs them)."""
        return self._native.initial_state(formulation, q, qdot, params)

    def rhs(self, t, x, formulation=None, params=None, momenta=None) -> np.ndarray:
        """``x' = f(t, x)`` of ``formulation``, as ``scipy.integrate.solve_ivp`` calls it."""
        return self._native.rhs(t, x, formulation, params, momenta)

    def jacobian(self, t, x, formulation=None, params=None, momenta=None) -> np.ndarray:
        """``d f / d x`` (n x n), exact from the derivation; ``solve_ivp``'s ``jac``."""
        return self._native.jacobian(t, x, formulation, params, momenta)

    def simulate(
        self,
        formulation=None,
        t_end=None,
        dt_out=None,
        method=None,
        rtol=None,
        atol=None,
        params=None,
        q=None,
        qdot=None,
        h=None,
        t_start=None,
        frame=None,
    ):
        """One formulation integrated with the model's events and monitored: the times, the
        coordinates and rates, the state, the energy (or its work balance) and its error, the
        momenta of the ignorable coordinates and the constraint residuals, one row per output
        time. A pandas DataFrame when pandas is installed (``frame=False`` for a
        ``Trajectory`` of numpy arrays). Defaults: the file's run, DOP853 at rtol = atol =
        1e-10 (the paper's DOPRI5 where the file asks for it); ``method`` is one of
        ``METHODS``. Ctrl-C stops the run within a few milliseconds (``KeyboardInterrupt``, its
        note saying the time reached). A run that stops early (a singular attitude, a matrix
        that turned singular) raises ``SimulationError`` whose ``trajectory`` holds the outputs
        up to the stop (``None`` when there were fewer than two). A run that DOPRI5 or DOP853
        finds stiff (Hairer's test: the step size held by stability, not accuracy) warns,
        naming the stiff method (``method="ros23"``)."""
        if frame is None:
            frame = _has_pandas()

        def made(kind, columns, table, events, used):
            result = Trajectory(columns, table, events, self.name, kind, zip(self.params, used), self.units)
            return result.to_pandas() if frame else result

        try:
            *columns, stiff = self._native.simulate_columns(formulation, t_end, dt_out, method, rtol, atol, h, params, q, qdot, t_start)
        except SimulationError as e:
            # A run that stopped early keeps its outputs up to the stop: ``e.trajectory``.
            partial = getattr(e, "partial", None)
            e.trajectory = None if partial is None else made(*partial)
            raise
        if stiff is not None:
            _warnings.warn(f"{self.name} {columns[0]}: {_stiff_advice(stiff)}", stacklevel=2)
        return made(*columns)

    def linearize(self, formulation=None, q=None, qdot=None, params=None) -> Linear:
        """The linear model about ``q``, ``qdot``: ``Linear(A, B, eigenvalues)``, B by the
        model's inputs."""
        return Linear(*self._native.linearize(formulation, q, qdot, params))

    def generate_rust(self, path, force: bool = False) -> None:
        """Writes the model's Rust module (as the ``generator`` command does) to ``path``,
        atomically; the model file itself or any ``.ron`` file is refused unless ``force``."""
        self._native.generate_rust(path, force)

    def animate(self, result, path=None) -> Optional["Animation"]:
        """Writes a self-contained HTML page (no network needed to view it) that plays
        ``result``, what ``simulate`` returned (a DataFrame or a ``Trajectory``), in 3-D: each
        body as its equivalent inertia box, each frame as its axes, with a time slider,
        play/pause and the time shown. ``#t=1.5`` after the page's address opens it paused at
        t = 1.5. A list of runs draws the first as the bodies and each other one over it, dashed
        in a colour of its own (the formulations at loose tolerances, to see them part; the
        first run's parameters are drawn). Without ``path``, returns the page as an
        :class:`Animation`, which a notebook shows inline."""
        if path is None:
            with _tempfile.TemporaryDirectory() as folder:
                page = _os.path.join(folder, f"{self.name}.html")
                self.animate(result, page)
                with open(page, encoding="utf-8") as f:
                    return Animation(f.read())
        results = list(result) if isinstance(result, (list, tuple)) else [result]
        if not results:
            raise ValueError("no run to animate: give what `simulate` returned, or a list of such runs")
        runs, params = [], None
        for one in results:
            attrs = getattr(one, "attrs", None)
            meta = attrs if attrs is not None and "params" in attrs else vars(one)
            if meta.get("model") not in (None, self.name):
                raise ValueError(f"the run is of model `{meta.get('model')}`, not of `{self.name}`: animate it with its own model")
            missing = [c for c in ["t", *self.coordinates] if c not in getattr(one, "columns", [])]
            if missing:
                raise ValueError(f"the run has no column {', '.join(map(repr, missing))}: give what `{self.name}`'s simulate returned")
            times = np.ascontiguousarray(np.asarray(one["t"], dtype=float))
            q = np.ascontiguousarray(np.column_stack([np.asarray(one[c], dtype=float) for c in self.coordinates]))
            runs.append((times, q, meta.get("formulation", "")))
            params = meta.get("params") if params is None else params
        self._native.animate(str(path), runs, params)


class Animation:
    """An animation page (``Model.animate`` without a path): a notebook shows it inline, in an
    isolated frame; ``save`` writes it.

    >>> import multibody
    >>> m = multibody.load("cart_pendulum")
    >>> page = m.animate(m.simulate(t_end=0.2))
    >>> page._repr_html_().startswith("<iframe")
    True
    """

    def __init__(self, html: str):
        self.html = html

    def _repr_html_(self) -> str:
        # The page's own scripts run in the frame, apart from the notebook's.
        return f'<iframe srcdoc="{_html.escape(self.html, quote=True)}" style="width: 100%; height: 540px; border: 0" sandbox="allow-scripts"></iframe>'

    def save(self, path) -> None:
        """Writes the page to ``path`` atomically (through a temporary file beside it), replacing
        a regular file there and refusing anything else (a directory, a link, a device)."""
        if _os.path.lexists(path) and not _stat.S_ISREG(_os.lstat(path).st_mode):
            raise FileExistsError(f"{path} exists and is not a regular file: give another name for the page")
        folder = _os.path.dirname(_os.path.abspath(path))
        fd, temporary = _tempfile.mkstemp(dir=folder, prefix=".animation-", suffix=".html")
        try:
            with _os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(self.html)
            _os.replace(temporary, path)
        except BaseException:
            if _os.path.exists(temporary):
                _os.unlink(temporary)
            raise

    def __repr__(self):
        return f"<multibody.Animation: {len(self.html)} characters of HTML>"


# Characters with a meaning in LaTeX's text mode, written as themselves.
_TEXT_ESCAPES = {c: "\\" + c for c in "{}_#$%&"}
_TEXT_ESCAPES.update({"\\": "\\textbackslash{}", "^": "\\textasciicircum{}", "~": "\\textasciitilde{}"})


def notebook_latex(text: str) -> str:
    """``inspect(latex=True)`` made into what a notebook renders: each
    ``\\begin{aligned} ... \\end{aligned}`` block inside ``$$ ... $$``, each line of text
    between them a display of its own: its prose as ``\\text{...}``, its ``$...$`` as math."""
    out, block = [], None
    for line in text.splitlines():
        stripped = line.strip()
        if block is not None:
            block.append(line)
            if stripped.startswith("\\end{aligned}"):
                out.append("$$" + "\n".join(block) + "$$")
                block = None
        elif stripped.startswith("\\begin{aligned}"):
            block = [line]
        elif stripped:
            # Prose as text, the expressions it holds (`$...$`) as math.
            parts = stripped.split("$")
            pieces = [
                "\\text{" + "".join(_TEXT_ESCAPES.get(c, c) for c in part) + "}" if k % 2 == 0 else part
                for k, part in enumerate(parts)
                if part
            ]
            out.append("$$" + " ".join(pieces) + "$$")
    return "\n".join(out)


def ensemble(
    model: Model,
    t_eval,
    params=None,
    q0=None,
    qdot0=None,
    formulation=None,
    method=None,
    rtol=None,
    atol=None,
    h=None,
    threads=None,
    return_reached=False,
    max_values=None,
):
    """N runs of ``model`` on every core (``threads`` to choose), the GIL released, each the
    same bytes as it would be alone: ``params`` (N, k) over every parameter in order, ``q0``
    and ``qdot0`` (N, m); any may be one row for all members or None for the model's own, and
    one at least is 2-D. Returns the states of ``formulation`` at ``t_eval`` (the first time is
    the start), an array (N, len(t_eval), states); with ``return_reached``, also how many output
    times each member reached (a terminal event stops a member early: its later rows are NaN,
    and a warning says which members stopped). A warning names the members that DOPRI5 or
    DOP853 found stiff (``method="ros23"`` may be much faster for them). Ctrl-C stops every
    member (``KeyboardInterrupt``).
    The output (N x len(t_eval) x states numbers) may hold at most ``max_values`` (default 10**8,
    800 MB), checked before anything runs; ``threads`` at most 16 per core."""
    arrays = _ensemble_arrays(model, t_eval, params, q0, qdot0, formulation, method, rtol, atol, h, threads, max_values)
    return _ensemble_result(*arrays, return_reached)


def _ensemble_arrays(
    model, t_eval, params=None, q0=None, qdot0=None, formulation=None, method=None, rtol=None, atol=None, h=None, threads=None, max_values=None
):
    """The ensemble's states, how many times each member reached, and the time from which
    each looked stiff (NaN: it did not)."""
    return _multibody.ensemble(
        model._native, np.asarray(t_eval, dtype=float), params, q0, qdot0, formulation, method, rtol, atol, h, threads, max_values
    )


def _stiff_advice(t):
    """What a run that looked stiff from ``t`` tells the user: the command line's words, then
    the stiff method as Python names it."""
    return f'{_multibody.stiffness_note(float(t))}: the stiff method may be much faster, method="ros23"'


def _ensemble_result(states, reached, stiff_at, return_reached):
    """What ``ensemble`` returns; a warning names the members that looked stiff (Hairer's test)
    and, without ``return_reached``, the members a terminal event stopped early."""
    stiff = np.flatnonzero(~np.isnan(stiff_at))
    if stiff.size:
        first = int(stiff[0])
        _warnings.warn(
            f"{stiff.size} member{'s' if stiff.size > 1 else ''} looked stiff: member {first} {_stiff_advice(stiff_at[first])}: "
            f"members {stiff[:10].tolist()}",
            stacklevel=3,
        )
    stopped = np.flatnonzero(reached < states.shape[1])
    if stopped.size and not return_reached:
        _warnings.warn(
            f"{stopped.size} members stopped early at a terminal event (rows after it are NaN): members {stopped[:10].tolist()}",
            stacklevel=3,
        )
    return (states, reached) if return_reached else states
