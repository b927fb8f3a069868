"""The wheel's in-process evaluation against the committed modules built by rustc, and the
model API: names, states, errors."""

import math
import os
import pickle

import numpy as np
import pytest

import multibody


def test_every_built_in_model_matches_its_compiled_module(compiled_rhs):
    built_in = set(multibody.built_in())
    seen = set()
    for entry in compiled_rhs:
        if entry["model"] not in built_in:
            continue  # a variant emitted with other options (baked, split, ...)
        model = multibody.load(entry["model"])
        kind = entry["formulation"]
        assert kind in model.formulations
        for state in entry["states"]:
            x = np.array(state["x"])
            want = np.array(state["rhs"])
            got = model.rhs(entry["t"], x, kind, params=entry["params"], momenta=entry["momenta"] or None)
            scale = max(1.0, np.max(np.abs(want)))
            assert np.max(np.abs(got - want)) <= 1e-13 * scale, (entry["model"], kind, got - want)
        seen.add(entry["model"])
    assert seen == built_in


def test_names_and_defaults():
    m = multibody.load("cart_pendulum")
    assert m.name == "cart_pendulum"
    assert m.coordinates == ["theta1", "theta2", "x"]
    assert m.formulations == ["lagrange", "maggi", "kane", "reduced_volterra"]
    assert m.ignorable == ["x"]
    assert list(m.params)[0:1] and all(isinstance(v, float) for v in m.params.values())
    names = m.state_names("kane")
    x, momenta = m.initial_state("kane")
    assert len(names) == len(x) and len(momenta) == 1
    # The same formulation by its alias.
    assert m.state_names("reduced") == m.state_names("reduced_volterra")


def test_values_by_name_or_in_order():
    m = multibody.load("three_body")
    q0, qd0 = m.initial
    assert m.coordinates[0] == "psi"
    by_name, _ = m.initial_state("kane", q={"psi": 0.7})
    in_order, _ = m.initial_state("kane", q=[0.7] + list(q0[1:]))
    assert np.array_equal(by_name, in_order)
    assert not np.array_equal(by_name, m.initial_state("kane")[0])
    heavier = dict(m.params)
    first = next(iter(heavier))
    heavier[first] *= 3.0
    x, _ = m.initial_state("kane")
    assert not np.array_equal(m.rhs(0.0, x, "kane"), m.rhs(0.0, x, "kane", params=heavier))
    assert np.array_equal(m.rhs(0.0, x, "kane", params={first: heavier[first]}), m.rhs(0.0, x, "kane", params=heavier))


def test_the_reduced_form_needs_its_momenta():
    m = multibody.load("cart_pendulum")
    x, momenta = m.initial_state("reduced")
    with pytest.raises(ValueError, match="momenta"):
        m.rhs(0.0, x, "reduced")
    assert np.all(np.isfinite(m.rhs(0.0, x, "reduced", momenta=momenta)))


def test_bad_arguments_are_value_errors_that_say_why():
    m = multibody.load("cart_pendulum")
    x, _ = m.initial_state("kane")
    with pytest.raises(ValueError, match="no formulation `hamilton`"):
        m.rhs(0.0, x, "hamilton")
    with pytest.raises(ValueError, match="x has 3 values, the formulation has"):
        m.rhs(0.0, x[:3], "kane")
    with pytest.raises(ValueError, match="no parameter `mass`"):
        m.rhs(0.0, x, "kane", params={"mass": 1.0})
    with pytest.raises(ValueError, match="not finite"):
        m.initial_state("kane", q={"x": math.nan})
    with pytest.raises(ValueError, match="no method `euler`"):
        m.simulate("kane", t_end=0.1, method="euler")


def test_a_model_error_names_the_file_line_and_fix(tmp_path):
    bad = tmp_path / "bad.ron"
    text = multibody.load("cart_pendulum").text.replace('mass: "m1"', 'mass: "m1 +"', 1)
    assert text != multibody.load("cart_pendulum").text
    bad.write_text(text)
    with pytest.raises(multibody.ModelError) as info:
        multibody.load(bad)
    message = str(info.value)
    assert str(bad) in message
    line = text[: text.index('mass: "m1 +"')].count("\n") + 1
    assert f":{line}:" in message
    with pytest.raises(multibody.ModelError, match="no model `nothing_here`"):
        multibody.load("nothing_here")
    with pytest.raises(multibody.ModelError, match="<mine>"):
        multibody.loads("Model(", name="<mine>")


def test_loads_is_load_of_the_text():
    a = multibody.load("three_body")
    b = multibody.loads(a.text, name="three_body.ron")
    x, _ = a.initial_state("kane")
    assert np.array_equal(a.rhs(0.1, x, "kane"), b.rhs(0.1, x, "kane"))


def test_a_model_pickles_as_its_text():
    a = multibody.load("three_body")
    b = pickle.loads(pickle.dumps(a))
    assert b.text == a.text and b.file == a.file
    x, _ = a.initial_state("kane")
    assert np.array_equal(a.rhs(0.0, x, "kane"), b.rhs(0.0, x, "kane"))


def test_inspect_and_notebook_latex():
    m = multibody.load("cart_pendulum")
    text = m.inspect()
    assert "mass matrix" in text and "reduced_volterra" in text
    latex = m._repr_latex_()
    blocks = latex.split("\n$$")
    assert latex.count("\\begin{aligned}") == latex.count("\\end{aligned}") > 0
    # Every line of display math is closed, and braces balance in each.
    displays = [d for d in latex.replace("\n", " ").split("$$") if d.strip()]
    for d in displays:
        depth = 0
        for i, c in enumerate(d):
            if c in "{}" and (i == 0 or d[i - 1] != "\\"):
                depth += 1 if c == "{" else -1
                assert depth >= 0, d
        assert depth == 0, d
    assert len(blocks) > 3


def katex(root):
    """KaTeX from npm, in target/ (installed on first use; needs node and npm)."""
    import shutil
    import subprocess

    folder = root / "target" / "katex"
    module = folder / "node_modules" / "katex"
    if not module.is_dir():
        assert shutil.which("npm"), "the LaTeX test renders with KaTeX: it needs node and npm"
        subprocess.run(["npm", "install", "--silent", "--prefix", str(folder), "katex@0.16"], check=True)
    return module


@pytest.mark.parametrize("name", ["cart_pendulum", "three_body", "rolling_disk", "tumbling_body", "winch"])
def test_the_notebook_latex_renders(root, name):
    """Every display block of `_repr_latex_` renders in KaTeX, strictly: the notebook shows
    equations, not errors."""
    import subprocess

    latex = multibody.load(name)._repr_latex_()
    # Every expression is math: no backslash is left in the prose.
    assert "\\textbackslash" not in latex
    script = root / "python" / "tests" / "render_latex.js"
    out = subprocess.run(["node", str(script), str(katex(root))], input=latex, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-3000:]
    assert int(out.stdout) == latex.count("$$") // 2 > 10


def test_generate_rust_writes_what_the_generator_writes(tmp_path, root, monkeypatch):
    import subprocess

    out = tmp_path / "cart_pendulum.rs"
    monkeypatch.chdir(root)
    multibody.load("models/cart_pendulum.ron").generate_rust(out)
    # `MULTIBODY_GENERATOR` names a generator binary already built (.ci/python: the test build's).
    generator = os.environ.get("MULTIBODY_GENERATOR")
    command = [generator] if generator else ["cargo", "run", "--release", "-q", "-p", "generator", "--"]
    command += ["models/cart_pendulum.ron", "--quiet"]
    expected = subprocess.run(command, cwd=root, check=True, capture_output=True, text=True).stdout
    assert out.read_text() == expected
    assert "pub fn model()" in expected


def test_generate_rust_never_writes_over_a_model(tmp_path, root):
    model_file = tmp_path / "mine.ron"
    text = (root / "models" / "cart_pendulum.ron").read_text()
    model_file.write_text(text)
    m = multibody.load(model_file)
    with pytest.raises(ValueError, match="the model file itself"):
        m.generate_rust(model_file)
    other = tmp_path / "other.ron"
    other.write_text("kept")
    with pytest.raises(ValueError, match="a `.ron` file"):
        m.generate_rust(other)
    assert model_file.read_text() == text and other.read_text() == "kept"
    # A directory in the way is never replaced.
    (tmp_path / "taken.rs").mkdir()
    with pytest.raises(OSError):
        m.generate_rust(tmp_path / "taken.rs")
    assert (tmp_path / "taken.rs").is_dir()


def test_linearize_the_inverted_pendulum():
    m = multibody.load("inverted_pendulum")
    lin = m.linearize("kane", q={c: 0.0 for c in m.coordinates}, qdot={c: 0.0 for c in m.coordinates})
    n = len(m.state_names("kane"))
    assert lin.A.shape[0] == lin.A.shape[1] <= n
    # Upright and at rest: one eigenvalue with a positive real part (it falls).
    assert np.max(lin.eigenvalues.real) > 0.1
    assert lin.B.shape[0] == lin.A.shape[0]


def test_an_error_past_column_65535_is_a_model_error():
    # A model written on one line by a script: the error renderer panicked past column 65535,
    # which reached Python as a PanicException that `except Exception` does not catch.
    text = " ".join(line.split("//")[0] for line in multibody.load("cart_pendulum").text.splitlines())
    text = text.replace("Model(", "Model(" + " " * 70_000, 1).replace('"-l/2", "0"]', '"-lx/2", "0"]', 1)
    try:
        multibody.loads(text, name="wide.ron")
    except Exception as e:  # noqa: BLE001 - the point: an ordinary exception
        assert isinstance(e, multibody.ModelError)
        assert "wide.ron:1:" in str(e) and "unknown name `lx`" in str(e) and "…" in str(e)
    else:
        raise AssertionError("the model is refused")


def test_linearize_a_spinning_top_returns_and_warns(root):
    # A heavy top spun upright in quaternions: the eigenvalue iteration never returned (and
    # ignored Ctrl-C); the point is no equilibrium, and the warning says what A then means.
    m = multibody.load(root / "tests" / "fixtures" / "heavy_top.ron")
    with pytest.warns(UserWarning, match="not an equilibrium nor a steady motion"):
        lin = m.linearize("kane", q={"e0": 1.0, "e1": 0.0}, qdot={"e2": 0.0, "e3": 20.0})
    assert len(lin.eigenvalues) > 0
    assert abs(np.sum(lin.eigenvalues).real - np.trace(lin.A)) < 1e-9 * np.abs(lin.A).max()
    # numpy finds the same eigenvalues.
    mine = np.sort_complex(lin.eigenvalues)
    cyclic = lin.A.shape[0] - len(mine)
    theirs = np.sort_complex(np.linalg.eigvals(lin.A))
    assert cyclic >= 0 and np.allclose(np.sort_complex(np.concatenate([mine, np.zeros(cyclic)])), theirs, atol=1e-9)
