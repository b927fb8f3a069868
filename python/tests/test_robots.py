"""Robots from URDF in Python (the issue "Robots"): `multibody.load` reads a URDF with its base,
gravity and limits, runs it as any model, and locates a URDF's errors. The robot is the
branching tree written for the tests (tests/fixtures/urdf/tree.urdf)."""

from pathlib import Path

import numpy as np
import pytest

import multibody

TREE = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "urdf" / "tree.urdf"


def test_a_fixed_robot_is_named_after_its_joints():
    m = multibody.load(TREE)
    assert m.coordinates == ["waist", "left_shoulder", "right_shoulder", "left_elbow", "right_wrist"]
    assert "mass_torso" in m.params
    # Gravity pulls the arms down: the tree at rest is not at rest.
    x0, _ = m.initial_state("kane")
    assert np.max(np.abs(m.rhs(0.0, x0, "kane"))) > 0.1


def test_a_floating_robot_in_space_keeps_its_momenta():
    m = multibody.load(str(TREE), base="floating", gravity=(0, 0, 0))
    assert m.coordinates[:7] == ["base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz"]
    assert m.ignorable == ["base_x", "base_y", "base_z"]
    qdot = {"waist": 1.0, "left_elbow": -0.7, "base_x": 0.2}
    ends = {}
    for kind in m.formulations:
        run = m.simulate(kind, t_end=0.5, dt_out=0.05, qdot=qdot, frame=False)
        assert np.max(np.abs(run["energy_error"])) < 1e-9, kind
        for c in m.ignorable:
            p = run[f"momentum:{c}"]
            assert np.max(np.abs(p - p[0])) < (1e-12 if kind == "reduced_volterra" else 1e-8), (kind, c)
        assert abs(run["momentum:base_x"][0]) > 0.1, "the base moves"
        ends[kind] = np.array([run[c][-1] for c in m.coordinates])
    for kind, end in ends.items():
        assert np.max(np.abs(end - ends["kane"])) < 1e-7, kind


def test_gravity_decides_what_is_ignorable():
    m = multibody.load(TREE, base="floating")
    assert m.ignorable == ["base_x", "base_y"]


def test_a_bad_urdf_is_located(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text(TREE.read_text().replace('type="revolute"', 'type="planar"', 1))
    with pytest.raises(multibody.ModelError) as info:
        multibody.load(bad)
    text = str(info.value)
    assert "bad.urdf" in text and "planar" in text, text
    line = next(i for i, l in enumerate(bad.read_text().splitlines(), 1) if 'type="planar"' in l)
    assert f":{line}:" in text, text


def test_a_base_that_is_neither_is_refused():
    with pytest.raises((ValueError, multibody.ModelError), match="floating"):
        multibody.load(TREE, base="flying")


def test_robot_options_for_a_model_that_is_no_urdf_are_refused():
    # They were silently ignored: a RON model sets its robot's in its `urdf` section.
    with pytest.raises(ValueError, match=r"base= is read for a URDF robot only, and `cart_pendulum` is not a URDF file"):
        multibody.load("cart_pendulum", base="floating")
    with pytest.raises(ValueError, match=r"gravity=, limits= are read for a URDF robot only"):
        multibody.load("three_body", gravity=(0, 0, 0), limits="stop")
    assert multibody.load("cart_pendulum").coordinates == ["theta1", "theta2", "x"]
