//! The `inspect` report: what was derived from a model, as text or LaTeX ([`crate::inspect`]
//! derives and writes it).

use crate::formulation::{Derivation, ignorable};
use crate::model::Model;
use crate::symbolic::Expr;
use crate::symbolic::print::render_shared;
use std::fmt::Write;

/// The report of a derivation, as text or LaTeX, with each formulation's assembly as
/// the emitter's assemblies give it.
pub(crate) fn report(model: &Model, d: &Derivation, assemblies: &[(String, String)], latex: bool) -> String {
    let mech = &d.mechanics;
    let reports = &d.reports;
    let chosen = &d.ignorable;
    let s = chosen.len();
    // An expression in a line of prose: inline math (`$...$`) in LaTeX.
    let show = |e: Expr| if latex { format!("${}$", e.to_latex()) } else { e.to_string() };
    let names: Vec<String> = model.coordinates.iter().map(|q| q.name()).collect();
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(w, "model: {} ({})", model.name, model.file);
    if !model.description.is_empty() {
        let _ = writeln!(w, "{}", model.description);
    }
    let _ = writeln!(w, "m = {}, r = {}, p = {}, s = {}, p - s = {}", mech.m, mech.r, mech.p, s, mech.p.saturating_sub(s));
    let _ = writeln!(w, "coordinates q = [{}]", names.join(", "));
    if !model.def.units.is_empty() {
        let units: Vec<String> = model.def.units.keys().map(|name| model.labelled(name)).collect();
        let _ = writeln!(w, "units: {}", units.join(", "));
    }
    let ign: Vec<&str> = chosen.iter().map(|&j| names[j].as_str()).collect();
    let _ = writeln!(
        w,
        "ignorable coordinates used by the reduced method: [{}] ({})",
        ign.join(", "),
        if model.declared_ignorable.is_some() { "declared, verified" } else { "detected" }
    );
    // The paper's Table 1: states and equations per method (the work integral adds a state
    // where applied forces can do work).
    let work = mech.q_forces.iter().any(|q| !q.is_zero());
    let _ = writeln!(w, "\nstates and equations per formulation (paper Table 1){}:", if work { ", the work integral W included" } else { "" });
    for e in &d.equations {
        let _ = writeln!(w, "  {:<17} {:>3} states, {:>3} equations", e.name(), e.states(work), e.equations);
    }
    let _ = writeln!(w, "\nhow each right-hand side assembles and solves its matrix (the plan the emitted code and the evaluator follow):");
    for e in &d.equations {
        let how = assemblies.iter().find(|(name, _)| name == e.name()).map_or_else(|| crate::emit::Solve::for_equations(e).describe(), |(_, how)| how.clone());
        let _ = writeln!(w, "  {:<17} {}: {how}", e.name(), e.matrix_name);
    }
    let mut items = vec![("T".to_string(), mech.kinetic), ("V".to_string(), mech.potential)];
    section(w, "energies:", &mut items, latex);
    let mut items = Vec::new();
    for i in 0..mech.m {
        for j in i..mech.m {
            items.push((sub("M", &[i + 1, j + 1], latex), mech.mass.get(i, j)));
        }
    }
    section(w, "mass matrix M (nonzero entries, upper triangle):", &mut items, latex);
    let mut items: Vec<(String, Expr)> = (0..mech.m).map(|i| (sub("N", &[i + 1], latex), mech.n[i])).collect();
    items.push((if latex { "T_{0}" } else { "T0" }.to_string(), mech.t0));
    section(w, "N and T0 (nonzero entries):", &mut items, latex);
    let mut items: Vec<(String, Expr)> = (0..mech.m).map(|i| (sub("Q", &[i + 1], latex), mech.q_forces[i])).collect();
    section(w, "generalized forces Q (nonzero entries; potential forces are in V):", &mut items, latex);
    let mut items = Vec::new();
    for i in 0..mech.r {
        for j in 0..mech.m {
            items.push((sub("a", &[i + 1, j + 1], latex), mech.a.get(i, j)));
        }
        items.push((sub("b", &[i + 1], latex), mech.b[i]));
    }
    section(w, "constraints a q' + b = 0 (nonzero entries):", &mut items, latex);
    let v = d.reduced.as_ref().expect("inspect derives the reduced form");
    let u_names: Vec<String> = v.u.iter().zip(&model.quasi_reduced).map(|(u, e)| format!("{} = {}", u.name(), show(*e))).collect();
    let _ = writeln!(w, "\nreduced Volterra method (Eqs. 42-67), u_NI: {}", u_names.join("; "));
    let _ = writeln!(w, "  elimination: {}", v.route);
    let g_names: Vec<String> = v.g.iter().map(|g| g.name()).collect();
    if !g_names.is_empty() {
        let _ = writeln!(w, "  G_I = [{}]: conserved momenta, computed from the initial state (Eq. 26)", g_names.join(", "));
    }
    match v.determinant {
        Some(d) => {
            let _ = writeln!(w, "  det [Y_NI; M'; a] = {}", show(d));
        }
        None => {
            let _ = writeln!(w, "  det [Y_NI; M'; a]: not expanded ({} x {})", mech.m, mech.m);
        }
    }
    let sing: Vec<String> = v.singular_factors.iter().map(|e| show(mech.tidy.of(*e))).collect();
    if sing.is_empty() {
        let _ = writeln!(w, "  the choice of quasi-velocities is regular at every state");
    } else {
        let _ = writeln!(w, "  singular only where one of these vanishes: {}", sing.join(", "));
    }
    let mut items = Vec::new();
    for i in 0..mech.m {
        for k in 0..v.u.len() {
            items.push((sub("W", &[i + 1, k + 1], latex), v.w.get(i, k)));
        }
        items.push((sub("X", &[i + 1], latex), v.x[i]));
    }
    section(w, "q' = W_NI u_NI + X_NI (nonzero entries):", &mut items, latex);
    let mut items = Vec::new();
    for i in 0..v.u.len() {
        for j in i..v.u.len() {
            items.push((sub("M_NI", &[i + 1, j + 1], latex), v.mass_ni.get(i, j)));
        }
    }
    for i in 0..v.u.len() {
        items.push((sub("L_NI", &[i + 1], latex), v.l_ni[i]));
    }
    section(w, "M_NI u_NI' = L_NI:", &mut items, latex);
    let needed = crate::formulation::reduced::needed(model, v);
    let _ = writeln!(w, "\nDefinition 1, coordinate by coordinate:");
    for r in reports {
        match &r.failure {
            None => {
                let verdict = needed.iter().find(|(j, _)| *j == r.index).map(|(_, p)| p.clone());
                let drop = match (&verdict, r.appears_in.is_empty()) {
                    (Some(None), _) => "the reduced equations are free of it (it can leave the integrated state)".to_string(),
                    (Some(Some(place)), _) => format!("but {place} depends on it (it must stay in the integrated state)"),
                    (None, true) => "a, b and Q are free of it too (not used by the reduced method)".to_string(),
                    (None, false) => format!("but it appears in {} (not used by the reduced method)", r.appears_in.join(", ")),
                };
                let _ = writeln!(w, "  {}: ignorable; {drop}", r.name);
            }
            Some(f) => {
                let _ = writeln!(w, "  {}: not ignorable: {}", r.name, if latex { latex_failure(f) } else { f.to_string() });
            }
        }
    }
    if !model.events.is_empty() {
        let name = |n: &str| if latex { format!("\\text{{{}}}", n.replace('_', "\\_")) } else { n.to_string() };
        let mut items = Vec::new();
        for e in &model.events {
            items.push((format!("g[{}] ({} crossing, {})", name(&e.name), e.direction.name(), e.action.name()), e.when));
            let resets = e.reset_q.iter().zip(&model.coordinates).map(|(r, q)| (r, q.name()));
            let rate_resets = e.reset_qdot.iter().zip(&model.coordinates).map(|(r, q)| (r, format!("{}'", q.name())));
            for (r, target) in resets.chain(rate_resets) {
                if let Some(r) = r {
                    items.push((format!("{} after {}", name(&target), name(&e.name)), *r));
                }
            }
        }
        section(w, "Events (g(t, q, q') crossing zero) and their resets:", &mut items, latex);
    }
    let mut cuts = Vec::new();
    let simplified = mech.tidy.report();
    if let Some(cut) = simplified.summary() {
        cuts.push(format!("simplifier: {cut}: exact, only larger"));
    }
    cuts.extend(d.cuts.lines());
    if !cuts.is_empty() {
        let _ = writeln!(w, "\nBudgets and undecided questions:");
        for line in cuts {
            let _ = writeln!(w, "  {line}");
        }
    }
    out
}

/// Subexpressions at most this large (tree nodes) are printed in place, larger shared ones once
/// under a name.
const INLINE_TREE: u32 = 40;

/// A titled list of `lhs = rhs` lines (zero entries left out), with the shared
/// subexpressions of the whole list named once after it.
fn section(w: &mut String, title: &str, items: &mut Vec<(String, Expr)>, latex: bool) {
    items.retain(|(_, e)| !e.is_zero());
    let _ = writeln!(w, "\n{title}");
    let exprs: Vec<Expr> = items.iter().map(|(_, e)| *e).collect();
    let (texts, defs) = render_shared(&exprs, latex, INLINE_TREE);
    let (eq, end) = if latex { (" &= ", " \\\\") } else { (" = ", "") };
    if latex {
        let _ = writeln!(w, "\\begin{{aligned}}");
    }
    for ((lhs, _), rhs) in items.iter().zip(&texts) {
        let _ = writeln!(w, "  {lhs}{eq}{rhs}{end}");
    }
    if !defs.is_empty() {
        let _ = writeln!(w, "  {}", if latex { "\\text{where}" } else { "where" });
        for (name, text) in &defs {
            let _ = writeln!(w, "  {name}{eq}{text}{end}");
        }
    }
    if latex {
        let _ = writeln!(w, "\\end{{aligned}}");
    }
}

fn latex_failure(f: &ignorable::Failure) -> String {
    match f {
        ignorable::Failure::InLagrangian { place, derivative, .. } => format!("L depends on it through {place}, derivative ${}$", derivative.to_latex()),
        ignorable::Failure::InConstraint { constraint, entry } => format!("column of a nonzero in `{constraint}`: ${}$", entry.to_latex()),
        ignorable::Failure::Forced { force } => format!("generalized force ${}$", force.to_latex()),
    }
}

fn sub(name: &str, idx: &[usize], latex: bool) -> String {
    let i: Vec<String> = idx.iter().map(|x| x.to_string()).collect();
    if latex { format!("{name}_{{{}}}", i.join("")) } else { format!("{name}[{}]", i.join("][")) }
}
