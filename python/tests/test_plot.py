"""`multibody.plot` draws a run: the chosen coordinates, the invariants' errors on a logarithmic
axis (what the reduced method keeps to round-off and what Kane's form lets drift), and the
momenta."""

import io

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

import multibody


def lines(ax):
    return {line.get_label(): line for line in ax.get_lines()}


def test_the_panels_show_the_coordinates_the_errors_and_the_momenta():
    m = multibody.load("three_body")
    reduced = m.simulate("reduced", t_end=5)
    fig = multibody.plot(reduced, coordinates=["psi", "X"])
    q, err, p = fig.axes
    assert (q.get_yscale(), err.get_yscale(), p.get_yscale()) == ("linear", "log", "linear")
    assert set(lines(q)) == {"psi", "X"}
    assert np.array_equal(lines(q)["psi"].get_ydata(), reduced["psi"].to_numpy())
    assert set(lines(p)) == {"X", "Y", "Z"}
    drift = {k: np.nanmax(v.get_ydata()) for k, v in lines(err).items() if k.startswith("|drift")}
    assert len(drift) == 3
    # The reduced method keeps the momenta to round-off; Kane's form lets them drift.
    assert max(drift.values()) < 1e-11, drift
    kane = multibody.plot(m.simulate("kane", t_end=5))
    kane_drift = [np.nanmax(v.get_ydata()) for k, v in lines(kane.axes[1]).items() if k.startswith("|drift")]
    assert min(kane_drift) > 1e-9, kane_drift
    # Every coordinate by default; the figure renders to a picture.
    assert len(lines(kane.axes[0])) == len(m.coordinates)
    png = io.BytesIO()
    kane.savefig(png, format="png")
    assert png.getbuffer().nbytes > 20_000
    assert "three_body (kane)" == kane._suptitle.get_text()


def test_a_series_zero_throughout_is_named_not_drawn():
    m = multibody.load("three_body")
    fig = m.simulate("kane", t_end=1, frame=False).plot()  # a Trajectory draws itself too
    labels = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    # Scene 2 has no constraint: its residuals are zero, listed in the legend and not drawn.
    assert any(label.startswith("zero throughout:") and "constraint residual" in label for label in labels), labels
    assert not any("constraint" in k for k in lines(fig.axes[1]))


def test_a_model_without_ignorable_coordinates_says_so():
    m = multibody.load("spring_cart")
    assert m.ignorable == []
    fig = multibody.plot(m.simulate(m.formulations[0], t_end=1))
    assert fig.axes[2].get_lines() == []
    assert fig.axes[2].texts[0].get_text() == "no ignorable coordinate"


def test_an_unknown_coordinate_names_the_known_ones():
    m = multibody.load("cart_pendulum")
    with pytest.raises(KeyError, match="no coordinate 'theta3'.*theta1, theta2, x"):
        multibody.plot(m.simulate("kane", t_end=1), coordinates=["theta3"])


def test_units_label_the_plot():
    m = multibody.load("cart_pendulum")
    assert m.units["x"] == "m" and m.units["theta1"] == "rad" and m.units["g"] == "m/s^2"
    run = m.simulate("kane", t_end=0.5, dt_out=0.1, frame=False)
    assert run.units == m.units and run.to_pandas().attrs["units"] == m.units
    for drawn in [run, run.to_pandas()]:
        fig = multibody.plot(drawn)
        labels = fig.axes[0].get_legend_handles_labels()[1]
        assert labels == ["theta1 [rad]", "theta2 [rad]", "x [m]"], labels
    # A model without units: the bare names.
    three = multibody.load("three_body")
    assert three.units == {}
    fig = multibody.plot(three.simulate("kane", t_end=0.2, dt_out=0.1, frame=False), coordinates=["psi"])
    assert fig.axes[0].get_legend_handles_labels()[1] == ["psi"]
