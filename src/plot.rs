//! SVG plots like the paper's figures: generalized coordinates over time, and the energy,
//! constraint and momentum errors over time, one curve per method. SVG needs no font files.

use files::write_creating_folder as write_atomic;
use plotters::prelude::*;
use runtime::compare::Run;
use runtime::monitor::Invariants;
use seam::Model;
use std::path::{Path, PathBuf};

const COLORS: [RGBColor; 6] =
    [RGBColor(31, 119, 180), RGBColor(255, 127, 14), RGBColor(44, 160, 44), RGBColor(214, 39, 40), RGBColor(148, 103, 189), RGBColor(140, 86, 75)];

/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write plot `{path}`: {message}")]
pub struct PlotError {
    pub path: String,
    pub message: String,
}

fn err(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError { path: files::printable_path(path), message: e.to_string() }
}

/// A tick label that reads as a number: `0.6`, `-12.5`, `1e-12`, `3e5`.
fn tick(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// One panel of series over `times` on linear axes, labelled, with the legend below the plot
/// area (never over the data).
fn panel(area: &DrawingArea<SVGBackend, plotters::coord::Shift>, title: &str, y_label: &str, times: &[f64], series: &[(&str, Vec<f64>)]) -> Result<(), String> {
    let (t0, t1) = (times[0], *times.last().unwrap_or(&1.0));
    let finite = series.iter().flat_map(|(_, s)| s.iter().copied()).filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = if hi > lo { 0.05 * (hi - lo) } else { (lo.abs() * 0.1).max(1e-12) };
    let (plot, legend) = area.split_vertically(area.dim_in_pixel().1.saturating_sub(22));
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(64)
        .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
        .map_err(|e| e.to_string())?;
    // A tick that is zero up to round-off of the axis' span reads as 0, not as -2e-16.
    let (x_span, y_span) = (t1 - t0, hi - lo + 2.0 * pad);
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(y_label)
        .x_label_formatter(&|v| if v.abs() < 1e-9 * x_span { "0".into() } else { tick(*v) })
        .y_label_formatter(&|v| if v.abs() < 1e-9 * y_span { "0".into() } else { tick(*v) })
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (_, values)) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(times.iter().copied().zip(values.iter().copied()).filter(|(_, v)| v.is_finite()), color.stroke_width(1)))
            .map_err(|e| e.to_string())?;
    }
    legend_row(&legend, series.iter().map(|(n, _)| *n))
}

/// One panel of `|series|` over `times` on a logarithmic axis (1e-15 and 1e-2 apart), zeros
/// drawn at the floor `1e-17`.
fn log_panel(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    title: &str,
    y_label: &str,
    times: &[f64],
    series: &[(&str, Vec<f64>)],
) -> Result<(), String> {
    const FLOOR: f64 = 1e-17;
    let (t0, t1) = (times[0], *times.last().unwrap_or(&1.0));
    let magnitudes: Vec<(&str, Vec<f64>)> = series.iter().map(|(n, s)| (*n, s.iter().map(|v| v.abs().max(FLOOR)).collect())).collect();
    let hi = magnitudes.iter().flat_map(|(_, s)| s.iter().copied()).filter(|v| v.is_finite()).fold(FLOOR * 10.0, f64::max);
    // At least two decades, so that the axis has ticks even when every value is the same.
    let lo = magnitudes.iter().flat_map(|(_, s)| s.iter().copied()).filter(|v| v.is_finite()).fold(hi, f64::min).min(hi / 100.0);
    let exact = series.iter().all(|(_, s)| s.iter().all(|v| *v == 0.0));
    let title = if exact { format!("{title}: exactly 0 at every output (drawn at 1e-17)") } else { title.to_string() };
    let (plot, legend) = area.split_vertically(area.dim_in_pixel().1.saturating_sub(22));
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(64)
        // The axis is log10 of the values on a linear scale, labelled with the values: plotters'
        // own logarithmic axis gave a panel spanning three decades near 1e-16 a single label.
        .build_cartesian_2d(t0..t1, (lo / 3.0).log10()..(hi * 3.0).log10())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(10f64.powf(*v)))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (_, values)) in magnitudes.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let points = times.iter().copied().zip(values.iter().map(|v| v.log10())).filter(|(_, v)| v.is_finite());
        chart.draw_series(LineSeries::new(points, color.stroke_width(1))).map_err(|e| e.to_string())?;
    }
    legend_row(&legend, magnitudes.iter().map(|(n, _)| *n))
}

/// The series' names in a row, each with its colour.
fn legend_row<'a>(area: &DrawingArea<SVGBackend, plotters::coord::Shift>, names: impl Iterator<Item = &'a str>) -> Result<(), String> {
    let mut x = 72;
    for (k, name) in names.enumerate() {
        let color = COLORS[k % COLORS.len()];
        area.draw(&PathElement::new(vec![(x, 10), (x + 18, 10)], color.stroke_width(2))).map_err(|e| e.to_string())?;
        area.draw(&Text::new(name.to_string(), (x + 22, 4), ("sans-serif", 12))).map_err(|e| e.to_string())?;
        x += 30 + 7 * name.len() as i32;
    }
    Ok(())
}

/// Writes `<scene>_coordinates.svg` and `<scene>_errors.svg` into `dir`; returns their paths.
/// Error panels are `|error|` on logarithmic axes; a panel with nothing to show (no
/// constraints, no ignorable coordinates) is left out.
/// `source` gives the coordinates' units (`x [m]` on the axes).
pub fn write_plots(model: &Model, source: &generator::model::Model, runs: &[Run], dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let Some(first) = runs.first() else { return Ok(vec![]) };
    let scene = &first.record.scene;
    let times = &first.solution.times;
    let m = first.invariants.coordinates.first().map_or(0, |q| q.len());
    // Coordinates: one panel per coordinate.
    let path = dir.join(format!("{scene}_coordinates.svg"));
    let rows = m.div_ceil(2).max(1);
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 280 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&path, e))?;
    for (j, area) in root.split_evenly((rows, 2)).iter().enumerate().take(m) {
        let series: Vec<(&str, Vec<f64>)> = runs.iter().map(|r| (r.record.method.as_str(), r.invariants.coordinates.iter().map(|q| q[j]).collect())).collect();
        let name = model.coordinates.get(j).cloned().unwrap_or_else(|| format!("q{j}"));
        panel(area, &name, &source.labelled(&name), times, &series).map_err(|e| err(&path, e))?;
    }
    root.present().map_err(|e| err(&path, e))?;
    drop(root);
    write_atomic(&path, svg.as_bytes()).map_err(|e| err(&path, e))?;
    // Errors: energy, and constraint and momentum where the model has them.
    let epath = dir.join(format!("{scene}_errors.svg"));
    let named = |f: &dyn Fn(&Run) -> Vec<f64>| -> Vec<(&str, Vec<f64>)> { runs.iter().map(|r| (r.record.method.as_str(), f(r))).collect() };
    let mut panels: Vec<(&str, &str, Vec<(&str, Vec<f64>)>)> =
        vec![(model.energy_balance.title(), model.energy_balance.axis(), named(&|r| r.invariants.energy_error.clone()))];
    if !model.constraints.is_empty() {
        panels.push(("constraint error |a q' + b|", "|a q' + b|", named(&|r| r.invariants.velocity_constraint.clone())));
    }
    if !model.ignorable.is_empty() {
        let total = |r: &Run| (0..times.len()).map(|i| r.invariants.momentum_error.iter().map(|k| k[i] * k[i]).sum::<f64>().sqrt()).collect();
        panels.push(("momentum error |G_I(t) - G_I(0)|", "|G - G(0)|", named(&total)));
    }
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 280 * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&epath, e))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, (title, label, series)) in areas.iter().zip(&panels) {
        log_panel(area, title, label, times, series).map_err(|e| err(&epath, e))?;
    }
    root.present().map_err(|e| err(&epath, e))?;
    drop(areas);
    drop(root);
    write_atomic(&epath, svg.as_bytes()).map_err(|e| err(&epath, e))?;
    Ok(vec![path, epath])
}

/// A simulation's plots: `<base>_coordinates.svg` (each coordinate over time) and
/// `<base>_invariants.svg` (|energy error|, the momenta's drift and the constraint residual,
/// where the model has them, on logarithmic axes).
/// `source` gives the coordinates' units (`x [m]` on the axes).
pub fn write_trajectory(
    model: &Model,
    source: &generator::model::Model,
    form: &seam::Formulation,
    times: &[f64],
    inv: &Invariants,
    base: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    let stem = base.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let path = base.with_file_name(format!("{stem}_coordinates.svg"));
    let m = model.coordinates.len();
    let rows = m.div_ceil(2).max(1);
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 280 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&path, e))?;
    for (j, area) in root.split_evenly((rows, 2)).iter().enumerate().take(m) {
        let name = &model.coordinates[j];
        let series = [(form.name(), inv.coordinates.iter().map(|q| q[j]).collect::<Vec<f64>>())];
        panel(area, name, &source.labelled(name), times, &series).map_err(|e| err(&path, e))?;
    }
    root.present().map_err(|e| err(&path, e))?;
    drop(root);
    write_atomic(&path, svg.as_bytes()).map_err(|e| err(&path, e))?;
    let ipath = base.with_file_name(format!("{stem}_invariants.svg"));
    let mut panels: Vec<(String, &str, Vec<(String, Vec<f64>)>)> =
        vec![(model.energy_balance.title().into(), model.energy_balance.axis(), vec![(model.energy_balance.quantity().into(), inv.energy_error.clone())])];
    if !model.ignorable.is_empty() {
        let series = model.ignorable.iter().zip(&inv.momentum_error).map(|(&j, s)| (model.coordinates[j].clone(), s.clone())).collect();
        panels.push(("momentum drift |G_I(t) - G_I(0)|, per ignorable coordinate".into(), "|G - G(0)|", series));
    }
    if !model.constraints.is_empty() {
        panels.push(("constraint residual |a q' + b|".into(), "|a q' + b|", vec![("velocity".into(), inv.velocity_constraint.clone())]));
    }
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 280 * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&ipath, e))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, (title, label, series)) in areas.iter().zip(&panels) {
        let series: Vec<(&str, Vec<f64>)> = series.iter().map(|(n, s)| (n.as_str(), s.clone())).collect();
        log_panel(area, title, label, times, &series).map_err(|e| err(&ipath, e))?;
    }
    root.present().map_err(|e| err(&ipath, e))?;
    drop(areas);
    drop(root);
    write_atomic(&ipath, svg.as_bytes()).map_err(|e| err(&ipath, e))?;
    Ok(vec![path, ipath])
}

/// The work-precision diagram: error against wall-clock time, log-log, one curve per formulation and
/// integrator (colour: formulation; marker: integrator).
pub fn write_work_precision(points: &[runtime::sweep::Point], path: &Path) -> Result<(), PlotError> {
    let ok: Vec<&runtime::sweep::Point> = points.iter().filter(|p| p.failure.is_none() && p.seconds > 0.0).collect();
    let floor = 1e-16;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        x0 = x0.min(p.seconds);
        x1 = x1.max(p.seconds);
        y0 = y0.min(p.error.max(floor));
        y1 = y1.max(p.error.max(floor));
    }
    if ok.is_empty() {
        return Err(err(path, "no successful runs to plot"));
    }
    let scene = &ok[0].scene;
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1000, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{scene}: work-precision (max |q - q_ref| against time per run)"), ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0 / 3.0..y1 * 3.0).log_scale())
        .map_err(|e| err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("wall-clock seconds per run")
        .y_desc("max error in q")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(|e| err(path, e))?;
    let mut methods: Vec<&str> = ok.iter().map(|p| p.method.as_str()).collect();
    methods.dedup();
    methods.sort();
    methods.dedup();
    let mut integrators: Vec<&str> = ok.iter().map(|p| p.integrator.as_str()).collect();
    integrators.sort();
    integrators.dedup();
    for (mi, method) in methods.iter().enumerate() {
        let color = COLORS[mi % COLORS.len()];
        for (ii, integrator) in integrators.iter().enumerate() {
            let mut curve: Vec<(f64, f64)> =
                ok.iter().filter(|p| p.method == *method && p.integrator == *integrator).map(|p| (p.seconds, p.error.max(floor))).collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            if curve.is_empty() {
                continue;
            }
            let style = color.stroke_width(if ii == 0 { 2 } else { 1 });
            // The legend shows each series as drawn: its line and its integrator's marker.
            let marker = ii % 3;
            let series = chart.draw_series(LineSeries::new(curve.clone(), style)).map_err(|e| err(path, e))?.label(format!("{method} {integrator}"));
            let line = move |(x, y)| EmptyElement::at((x, y)) + PathElement::new(vec![(0, 0), (16, 0)], style);
            match marker {
                0 => series.legend(move |c| line(c) + Circle::new((8, 0), 3, color.filled())),
                1 => series.legend(move |c| line(c) + TriangleMarker::new((8, 0), 4, color.filled())),
                _ => series.legend(move |c| line(c) + Cross::new((8, 0), 4, color)),
            };
            match marker {
                0 => chart.draw_series(curve.iter().map(|&(x, y)| Circle::new((x, y), 3, color.filled()))),
                1 => chart.draw_series(curve.iter().map(|&(x, y)| TriangleMarker::new((x, y), 4, color.filled()))),
                _ => chart.draw_series(curve.iter().map(|&(x, y)| Cross::new((x, y), 4, color))),
            }
            .map_err(|e| err(path, e))?;
        }
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| err(path, e))?;
    root.present().map_err(|e| err(path, e))?;
    drop(chart);
    drop(root);
    write_atomic(path, svg.as_bytes()).map(|_| ()).map_err(|e| err(path, e))
}

/// The eigenvalues of a linearization sweep against the swept value: real parts (top) and
/// imaginary parts (bottom), one dot per eigenvalue, like the bicycle benchmark's figure.
pub fn write_eigenvalues(title: &str, swept: &str, rows: &[runtime::linearize::SweepRow], path: &Path) -> Result<(), PlotError> {
    let (v0, v1) = (rows.first().map_or(0.0, |r| r.value), rows.last().map_or(1.0, |r| r.value));
    let (v0, v1) = if v1 > v0 { (v0, v1) } else { (v0 - 1.0, v0 + 1.0) };
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1000, 760)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let areas = root.split_evenly((2, 1));
    for (area, (label, part)) in areas.iter().zip([("real part", 0usize), ("imaginary part", 1)]) {
        let values: Vec<(f64, f64)> =
            rows.iter().flat_map(|r| r.eigenvalues.iter().map(move |e| (r.value, if part == 0 { e.0 } else { e.1 }))).filter(|(_, y)| y.is_finite()).collect();
        let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (_, y)| (a.min(*y), b.max(*y)));
        let (lo, hi) = if lo.is_finite() && hi > lo { (lo, hi) } else { (-1.0, 1.0) };
        let pad = 0.05 * (hi - lo);
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{title}: eigenvalues, {label}"), ("sans-serif", 15))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(60)
            .build_cartesian_2d(v0..v1, (lo - pad)..(hi + pad))
            .map_err(|e| err(path, e))?;
        chart
            .configure_mesh()
            .x_desc(swept)
            .y_desc(label)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(|e| err(path, e))?;
        chart.draw_series(std::iter::once(PathElement::new(vec![(v0, 0.0), (v1, 0.0)], BLACK.stroke_width(1)))).map_err(|e| err(path, e))?;
        chart.draw_series(values.iter().map(|&(x, y)| Circle::new((x, y), 2, COLORS[part].filled()))).map_err(|e| err(path, e))?;
    }
    root.present().map_err(|e| err(path, e))?;
    drop(areas);
    drop(root);
    write_atomic(path, svg.as_bytes()).map(|_| ()).map_err(|e| err(path, e))
}

#[cfg(test)]
mod tests {
    /// The work-precision legend draws each integrator's marker beside its series' line: a
    /// circle, a triangle and a cross for three integrators.
    #[test]
    fn the_work_precision_legend_shows_the_markers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("wp.svg");
        let point = |integrator: &str, seconds: f64, error: f64| runtime::sweep::Point {
            scene: "s".into(),
            method: "kane".into(),
            integrator: integrator.into(),
            setting: 1e-6,
            seconds,
            rhs_calls: 100,
            steps: 10,
            error,
            energy_error_norm: 0.0,
            momentum_error_norm: 0.0,
            constraint_error_norm: 0.0,
            failure: None,
        };
        let points: Vec<_> = ["DOP853", "DOPRI5", "RK4"].iter().flat_map(|i| [point(i, 1e-4, 1e-8), point(i, 2e-4, 1e-10)]).collect();
        super::write_work_precision(&points, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        // Two points per series plus one in the legend: 3 circles; triangles are polygons.
        assert_eq!(svg.matches("<circle").count(), 3, "{svg}");
        assert_eq!(svg.matches("<polygon").count(), 3, "{svg}");
    }

    #[test]
    fn ticks_read_as_numbers() {
        let t = super::tick;
        assert_eq!([t(0.6), t(-12.5), t(1e-12), t(3e5), t(0.0), t(2.0)], ["0.6", "-12.5", "1e-12", "3e5", "0", "2"]);
    }

    /// The y labels of a logarithmic panel of `values`, in drawing order.
    fn log_labels(values: Vec<f64>) -> Vec<String> {
        use plotters::prelude::*;
        let mut svg = String::new();
        let times: Vec<f64> = (0..values.len()).map(|k| k as f64).collect();
        {
            let root = SVGBackend::with_string(&mut svg, (600, 300)).into_drawing_area();
            super::log_panel(&root, "drift", "|G - G(0)|", &times, &[("x", values)]).unwrap();
            root.present().unwrap();
        }
        svg.split("</text>")
            .filter_map(|t| t.rsplit('>').next())
            .map(|t| t.trim().to_string())
            .filter(|t| t.contains('e') && t.parse::<f64>().is_ok())
            .collect()
    }

    /// A panel spanning a few decades near round-off (the reduced method's momentum drift) has
    /// a label at every decade or closer: plotters' logarithmic axis gave it one.
    #[test]
    fn a_log_panel_near_round_off_has_numbers_on_its_axis() {
        let labels = log_labels((0..50).map(|k| if k % 3 == 0 { 0.0 } else { 1e-16 * (1.0 + (k % 7) as f64 * 4.0) }).collect());
        assert!(labels.len() >= 4, "{labels:?}");
        let values: Vec<f64> = labels.iter().map(|l| l.parse().unwrap()).collect();
        assert!(values.windows(2).all(|w| w[1] / w[0] <= 10.0 + 1e-9 || w[0] / w[1] <= 10.0 + 1e-9), "{labels:?}");
        // Twelve decades get labels too, and none reads as noise.
        let labels = log_labels((0..50).map(|k| 10f64.powi(-(k % 13))).collect());
        assert!(labels.len() >= 5 && labels.iter().all(|l| l.starts_with('1') || l.starts_with('3')), "{labels:?}");
    }
}
