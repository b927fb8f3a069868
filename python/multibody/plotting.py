"""A run drawn with matplotlib: the coordinates, the invariants' errors on logarithmic axes,
and the conserved momenta.

>>> import multibody
>>> m = multibody.load("three_body")
>>> fig = multibody.plot(m.simulate("reduced", t_end=2), coordinates=["psi", "X"])
>>> [ax.get_yscale() for ax in fig.axes]
['linear', 'log', 'linear']
"""

from __future__ import annotations

import numpy as np


def _column(run, name):
    return np.asarray(run[name], dtype=float)


def _meta(run, key, default):
    """What a run says of itself: a DataFrame's ``attrs`` or a ``Trajectory``'s attribute."""
    attrs = getattr(run, "attrs", None)
    if isinstance(attrs, dict) and "model" in attrs:
        return attrs.get(key, default)
    return getattr(run, key, default)


def _units(run):
    """The units of a run's coordinates and parameters (``units`` in the model file)."""
    return _meta(run, "units", {}) or {}


def _origin(run):
    """(model, formulation) of a DataFrame (its ``attrs``) or a ``Trajectory``."""
    return _meta(run, "model", ""), _meta(run, "formulation", "")


def plot(run, coordinates=None, *, title=None):
    """Draws a run of ``Model.simulate`` (a DataFrame or a ``Trajectory``) and returns the
    matplotlib ``Figure``, three panels over time:

    - the ``coordinates`` named (default: every coordinate of the model, at most eight), each
      labelled with its unit where the model gives one (``x [m]``);
    - the invariants' errors on a logarithmic axis: ``|energy error|`` (the energy balance
      ``E - E(0)``, work of non-potential forces included), each conserved momentum's drift
      ``|p(t) - p(0)|``, and the constraint residuals; a series that is zero throughout has
      nothing to show on a logarithmic axis and is left out (the legend says which are);
    - the conserved momenta of the ignorable coordinates themselves (empty when there are none).

    Needs matplotlib (``pip install matplotlib``); show the figure with ``plt.show()`` or save
    it with ``fig.savefig(path)``.
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - the message is the point
        raise ImportError("multibody.plot needs matplotlib: pip install matplotlib") from e
    columns = list(run.columns)
    known = [c for c in columns if c != "t" and not c.endswith("'") and ":" not in c and f"{c}'" in columns]
    if coordinates is None:
        coordinates = known[:8]
    else:
        coordinates = list(coordinates)
        unknown = [c for c in coordinates if c not in known]
        if unknown:
            raise KeyError(f"no coordinate {', '.join(map(repr, unknown))} in this run; its coordinates: {', '.join(known)}")
    t = _column(run, "t")
    fig, (ax_q, ax_err, ax_p) = plt.subplots(3, 1, sharex=True, figsize=(8, 9), constrained_layout=True)
    model, formulation = _origin(run)
    fig.suptitle(title if title is not None else f"{model} ({formulation})".strip())

    units = _units(run)
    for c in coordinates:
        ax_q.plot(t, _column(run, c), label=f"{c} [{units[c]}]" if c in units else c)
    ax_q.set_ylabel("coordinates")
    if coordinates:
        ax_q.legend(loc="best", fontsize="small", ncol=min(4, len(coordinates)))

    momenta = [c for c in columns if c.startswith("momentum:")]
    errors = []
    if "energy_error" in columns:
        errors.append(("|energy error|", np.abs(_column(run, "energy_error"))))
    for c in momenta:
        p = _column(run, c)
        errors.append((f"|drift of momentum {c.split(':', 1)[1]}|", np.abs(p - p[0])))
    for c in ("constraint_residual", "position_residual"):
        if c in columns:
            errors.append((f"|{c.replace('_', ' ')}|", np.abs(_column(run, c))))
    zero = []
    for label, values in errors:
        if np.any(values > 0):
            # Exact zeros (a momentum kept to the last bit at some outputs) are gaps, not -inf.
            ax_err.plot(t, np.where(values > 0, values, np.nan), label=label)
        else:
            zero.append(label)
    ax_err.set_yscale("log")
    ax_err.set_ylabel("errors")
    handles, labels = ax_err.get_legend_handles_labels()
    if zero:
        handles.append(plt.Line2D([], [], linestyle="none"))
        labels.append("zero throughout: " + ", ".join(zero))
    if labels:
        ax_err.legend(handles, labels, loc="best", fontsize="small")

    for c in momenta:
        ax_p.plot(t, _column(run, c), label=c.split(":", 1)[1])
    ax_p.set_ylabel("conserved momenta")
    if momenta:
        ax_p.legend(loc="best", fontsize="small")
    else:
        ax_p.text(0.5, 0.5, "no ignorable coordinate", transform=ax_p.transAxes, ha="center", va="center")
    ax_p.set_xlabel("t")
    return fig
