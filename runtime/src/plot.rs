//! SVG plots like the paper's figures: generalized coordinates over time, and the energy,
//! constraint and momentum errors over time, one curve per method. SVG needs no font files.

use crate::compare::Run;
use files::write_creating_folder as write_atomic;
use plotters::prelude::*;
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
    PlotError { path: path.display().to_string(), message: e.to_string() }
}

/// One panel: a titled chart of several series over `times`.
fn panel(area: &DrawingArea<SVGBackend, plotters::coord::Shift>, title: &str, times: &[f64], series: &[(&str, Vec<f64>)]) -> Result<(), String> {
    let (t0, t1) = (times[0], *times.last().unwrap_or(&1.0));
    let finite = series.iter().flat_map(|(_, s)| s.iter().copied()).filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 1e-300_f64.max(lo.abs() * 0.1).max(1e-16) };
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 14))
        .margin(8)
        .x_label_area_size(28)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
        .map_err(|e| e.to_string())?;
    chart.configure_mesh().x_desc("t [s]").y_label_formatter(&|v| format!("{v:.2e}")).draw().map_err(|e| e.to_string())?;
    for (k, (name, values)) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(times.iter().copied().zip(values.iter().copied()).filter(|(_, v)| v.is_finite()), color.stroke_width(1)))
            .map_err(|e| e.to_string())?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| e.to_string())?;
    Ok(())
}

/// Writes `<scene>_coordinates.svg` and `<scene>_errors.svg` into `dir`; returns their paths.
pub fn write_plots(model: &Model, runs: &[Run], dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    std::fs::create_dir_all(dir).map_err(|e| err(dir, e))?;
    let Some(first) = runs.first() else { return Ok(vec![]) };
    let scene = &first.record.scene;
    let times = &first.solution.times;
    let m = first.invariants.coordinates.first().map_or(0, |q| q.len());
    let names = model.coordinates;
    // Coordinates: one panel per coordinate.
    let path = dir.join(format!("{scene}_coordinates.svg"));
    let rows = m.div_ceil(2).max(1);
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 260 * rows as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&path, e))?;
    for (j, area) in root.split_evenly((rows, 2)).iter().enumerate().take(m) {
        let series: Vec<(&str, Vec<f64>)> = runs.iter().map(|r| (r.record.method.as_str(), r.invariants.coordinates.iter().map(|q| q[j]).collect())).collect();
        let title = names.get(j).map_or(format!("q{j}"), |n| n.to_string());
        panel(area, &title, times, &series).map_err(|e| err(&path, e))?;
    }
    root.present().map_err(|e| err(&path, e))?;
    drop(root);
    write_atomic(&path, svg.as_bytes()).map_err(|e| err(&path, e))?;
    // Errors: energy, constraint, momentum.
    let epath = dir.join(format!("{scene}_errors.svg"));
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1100, 780)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&epath, e))?;
    let areas = root.split_evenly((3, 1));
    let energy: Vec<(&str, Vec<f64>)> = runs.iter().map(|r| (r.record.method.as_str(), r.invariants.energy_error.clone())).collect();
    panel(&areas[0], "energy error E(t) - E(0) (E = T + V - W)", times, &energy).map_err(|e| err(&epath, e))?;
    let constraint: Vec<(&str, Vec<f64>)> = runs.iter().map(|r| (r.record.method.as_str(), r.invariants.velocity_constraint.clone())).collect();
    panel(&areas[1], "constraint error |a q' + b|", times, &constraint).map_err(|e| err(&epath, e))?;
    let momentum: Vec<(&str, Vec<f64>)> = runs
        .iter()
        .map(|r| {
            let s = &r.invariants.momentum_error;
            let total = (0..times.len()).map(|i| s.iter().map(|k| k[i] * k[i]).sum::<f64>().sqrt()).collect();
            (r.record.method.as_str(), total)
        })
        .collect();
    panel(&areas[2], "momentum error |G_I(t) - G_I(0)|", times, &momentum).map_err(|e| err(&epath, e))?;
    root.present().map_err(|e| err(&epath, e))?;
    drop(areas);
    drop(root);
    write_atomic(&epath, svg.as_bytes()).map_err(|e| err(&epath, e))?;
    Ok(vec![path, epath])
}

/// The work-precision diagram: error against CPU time, log-log, one curve per formulation and
/// integrator (colour: formulation; marker: integrator).
pub fn write_work_precision(points: &[crate::sweep::Point], path: &Path) -> Result<(), PlotError> {
    let ok: Vec<&crate::sweep::Point> = points.iter().filter(|p| p.failure.is_none() && p.cpu_seconds > 0.0).collect();
    let floor = 1e-16;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        x0 = x0.min(p.cpu_seconds);
        x1 = x1.max(p.cpu_seconds);
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
        .caption(format!("{scene}: work-precision (max |q - q_ref| against CPU time per run)"), ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0 / 3.0..y1 * 3.0).log_scale())
        .map_err(|e| err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("CPU seconds per run")
        .y_desc("max error in q")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
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
                ok.iter().filter(|p| p.method == *method && p.integrator == *integrator).map(|p| (p.cpu_seconds, p.error.max(floor))).collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            if curve.is_empty() {
                continue;
            }
            let style = color.stroke_width(if ii == 0 { 2 } else { 1 });
            chart
                .draw_series(LineSeries::new(curve.clone(), style))
                .map_err(|e| err(path, e))?
                .label(format!("{method} {integrator}"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
            match ii % 3 {
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
pub fn write_eigenvalues(title: &str, swept: &str, rows: &[crate::linearize::SweepRow], path: &Path) -> Result<(), PlotError> {
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
        chart.configure_mesh().x_desc(swept).y_desc(label).draw().map_err(|e| err(path, e))?;
        chart.draw_series(std::iter::once(PathElement::new(vec![(v0, 0.0), (v1, 0.0)], BLACK.stroke_width(1)))).map_err(|e| err(path, e))?;
        chart.draw_series(values.iter().map(|&(x, y)| Circle::new((x, y), 2, COLORS[part].filled()))).map_err(|e| err(path, e))?;
    }
    root.present().map_err(|e| err(path, e))?;
    drop(areas);
    drop(root);
    write_atomic(path, svg.as_bytes()).map(|_| ()).map_err(|e| err(path, e))
}
