//! Ensembles: one formulation of a model run from many parameter sets and initial conditions
//! on every core (rayon), each member integrated exactly as it would be alone, so that the
//! result is the same bytes whatever the number of threads.
//!
//! ```
//! use runtime::ensemble::{Member, ensemble};
//! use runtime::integrate::Settings;
//! use std::sync::atomic::AtomicBool;
//! let model = generated::cart_pendulum::model();
//! let kind = seam::FormulationKind::Kane;
//! let members: Vec<Member> = (0..4)
//!     .map(|k| Member { params: model.default_params.clone(), q0: vec![0.1 * k as f64, 0.0, 0.0], qd0: vec![0.0; 3] })
//!     .collect();
//! let times = [0.0, 0.5, 1.0];
//! let runs = ensemble(&model, kind, &members, &times, &Settings::tight(1.0), None, runtime::ensemble::DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false)).unwrap();
//! assert_eq!((runs.members, runs.times, runs.states), (4, 3, 6));
//! // Member 0 starts at rest in its equilibrium and stays there.
//! assert!(runs.member(0).iter().all(|x| x.abs() < 1e-12));
//! ```

use crate::events::run_interruptible;
use crate::integrate::{Reason, RunError, Settings};
use crate::system::{SetupError, System};
use rayon::prelude::*;
use seam::{FormulationKind, Model};
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

/// One run of an ensemble: its parameters (every one of the model's, in its order) and its
/// initial coordinates and rates.
#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    pub params: Vec<f64>,
    pub q0: Vec<f64>,
    pub qd0: Vec<f64>,
}

/// The states of every member at every output time, member by member.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectories {
    pub members: usize,
    pub times: usize,
    /// The formulation's state size (its `state_names`).
    pub states: usize,
    /// `members x times x states`, row-major: member `k`'s state at time `i` starts at
    /// `(k * times + i) * states`. A member stopped early by a terminal event holds NaN after
    /// its last reached time (`reached` says where).
    pub data: Vec<f64>,
    /// How many output times each member reached (`times` unless a terminal event stopped it).
    pub reached: Vec<usize>,
    /// Each member's time from which it looked stiff to DOPRI5 or DOP853 (Hairer's test, as
    /// [`crate::integrate::Stats::stiff_at`]); `None` where it did not.
    pub stiff_at: Vec<Option<f64>>,
}

/// One member's run ([`run_member`]): its states at the output times (NaN after a terminal
/// event), how many of the times it reached, and when it looked stiff.
#[derive(Clone, Debug, PartialEq)]
pub struct MemberRun {
    pub states: Vec<f64>,
    pub reached: usize,
    pub stiff_at: Option<f64>,
}

impl Trajectories {
    /// Member `k`'s states, `times x states`, row-major.
    pub fn member(&self, k: usize) -> &[f64] {
        &self.data[k * self.times * self.states..(k + 1) * self.times * self.states]
    }
}

/// Why an ensemble failed: the first failing member (by index, whatever the order the threads
/// finished in) and why.
#[derive(Debug, thiserror::Error)]
pub enum EnsembleError {
    #[error("ensemble member {member}: {source}")]
    Setup { member: usize, source: SetupError },
    #[error("ensemble member {member}: {source}")]
    Run { member: usize, source: RunError },
    #[error("ensemble member {member}: {what} has {got} values, the model has {expected}")]
    Shape { member: usize, what: &'static str, got: usize, expected: usize },
    #[error("the output times must start the run and increase (they are the integrator's output grid)")]
    Times,
    #[error("cannot start {threads} threads: {message}")]
    Threads { threads: usize, message: String },
    /// The output would hold more numbers than the caller allows (it is allocated whole).
    #[error(
        "the ensemble's output would hold {members} members x {times} times x {states} states = {values} numbers ({:.1} GB), more than the limit of {limit} ({:.1} GB): give fewer members or output times, or raise the limit (max_values)",
        *values as f64 * 8e-9,
        *limit as f64 * 8e-9
    )]
    TooLarge { members: usize, times: usize, states: usize, values: u128, limit: usize },
    /// The caller set the ensemble's `stop` flag (a Ctrl-C): the members running stopped at
    /// their last accepted step, the others never started.
    #[error("interrupted: the caller asked the ensemble to stop")]
    Interrupted,
}

/// One member run alone: its states at `times` (NaN after a terminal event), how many times
/// it reached, and when it looked stiff.
///
/// The run starts at `times[0]` from the member's `q0`, `qd0`; the model's events are watched.
/// It stops with [`EnsembleError::Interrupted`] once `stop` is set (read before every
/// right-hand side).
pub fn run_member(
    model: &Model,
    kind: FormulationKind,
    member: &Member,
    index: usize,
    times: &[f64],
    settings: &Settings,
    stop: &AtomicBool,
) -> Result<MemberRun, EnsembleError> {
    if stop.load(Ordering::Relaxed) {
        return Err(EnsembleError::Interrupted);
    }
    let shape = |what, got: usize, expected: usize| if got == expected { Ok(()) } else { Err(EnsembleError::Shape { member: index, what, got, expected }) };
    shape("params", member.params.len(), model.parameter_names.len())?;
    shape("q0", member.q0.len(), model.coordinates.len())?;
    shape("qd0", member.qd0.len(), model.coordinates.len())?;
    let (sys, y0) =
        System::start(model, kind, member.params.clone(), &member.q0, &member.qd0).map_err(|source| EnsembleError::Setup { member: index, source })?;
    let settings = Settings { time_independent: !sys.form.depends_on_time, ..*settings };
    let on_rhs = &mut |_| if stop.load(Ordering::Relaxed) { ControlFlow::Break(()) } else { ControlFlow::Continue(()) };
    let solution = run_interruptible(&sys, &y0, times, &settings, on_rhs)
        .map_err(|source| if source.reason == Reason::Interrupted { EnsembleError::Interrupted } else { EnsembleError::Run { member: index, source } })?
        .solution;
    let mut states: Vec<f64> = solution.states.iter().flatten().copied().collect();
    let reached = solution.states.len();
    states.resize(times.len() * y0.len(), f64::NAN);
    Ok(MemberRun { states, reached, stiff_at: solution.stats.stiff_at })
}

/// The most numbers an ensemble's output holds unless the caller allows more: 10^8, 800 MB
/// (the members' runs hold as much again while they run).
pub const DEFAULT_MAX_VALUES: usize = 100_000_000;

/// The most threads per core an ensemble starts: more only cost memory and time (each thread
/// runs whole members; ten thousand threads took a minute to start and stop).
pub const MAX_THREADS_PER_CORE: usize = 16;

/// Whether `threads` threads may run an ensemble on this machine ([`MAX_THREADS_PER_CORE`]).
pub fn check_threads(threads: usize) -> Result<(), EnsembleError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let most = MAX_THREADS_PER_CORE * cores;
    match threads {
        0 => Err(EnsembleError::Threads { threads, message: "an ensemble needs one thread at least".into() }),
        n if n > most => Err(EnsembleError::Threads {
            threads,
            message: format!("more than {MAX_THREADS_PER_CORE} per core ({cores} cores here, so at most {most}); more threads than cores only cost memory"),
        }),
        _ => Ok(()),
    }
}

/// Every member of `members` run with formulation `kind` over the output `times` (the first
/// is the start) under `settings`, in parallel on `threads` threads (all cores when `None`;
/// at most [`MAX_THREADS_PER_CORE`] per core); `on_done` is told of every member finished (for
/// progress). The output may hold at most `max_values` numbers ([`DEFAULT_MAX_VALUES`]),
/// checked before anything runs. Setting `stop` (from another thread: a Ctrl-C watcher) ends
/// the ensemble early with [`EnsembleError::Interrupted`].
pub fn ensemble(
    model: &Model,
    kind: FormulationKind,
    members: &[Member],
    times: &[f64],
    settings: &Settings,
    threads: Option<usize>,
    max_values: usize,
    on_done: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> Result<Trajectories, EnsembleError> {
    if times.is_empty() || !times.windows(2).all(|w| w[1] > w[0]) || !times.iter().all(|t| t.is_finite()) {
        return Err(EnsembleError::Times);
    }
    if let Some(n) = threads {
        check_threads(n)?;
    }
    let states = model.formulation(kind).map(|f| f.states()).ok_or_else(|| EnsembleError::Setup {
        member: 0,
        source: SetupError::UnknownFormulation {
            model: model.module.clone(),
            kind,
            available: model.kinds().iter().map(|k| k.name()).collect::<Vec<_>>().join(", "),
        },
    })?;
    let values = members.len() as u128 * times.len() as u128 * states as u128;
    if values > max_values as u128 {
        return Err(EnsembleError::TooLarge { members: members.len(), times: times.len(), states, values, limit: max_values });
    }
    let all = || -> Vec<Result<MemberRun, EnsembleError>> {
        members
            .par_iter()
            .enumerate()
            .map(|(k, member)| {
                let one = run_member(model, kind, member, k, times, settings, stop);
                on_done();
                one
            })
            .collect()
    };
    let results = match threads {
        None => all(),
        Some(n) => {
            rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| EnsembleError::Threads { threads: n, message: e.to_string() })?.install(all)
        }
    };
    if stop.load(Ordering::Relaxed) {
        return Err(EnsembleError::Interrupted);
    }
    let mut data = Vec::with_capacity(members.len() * times.len() * states);
    let mut reached = Vec::with_capacity(members.len());
    let mut stiff_at = Vec::with_capacity(members.len());
    for result in results {
        let run = result?;
        data.extend(run.states);
        reached.push(run.reached);
        stiff_at.push(run.stiff_at);
    }
    Ok(Trajectories { members: members.len(), times: times.len(), states, data, reached, stiff_at })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::events::run;

    fn members(model: &Model, n: usize) -> Vec<Member> {
        (0..n)
            .map(|k| {
                let s = k as f64 / n as f64;
                let mut params = model.default_params.clone();
                params[0] *= 1.0 + s;
                let q0 = (0..model.coordinates.len()).map(|j| 0.3 * s + 0.05 * j as f64).collect();
                let qd0 = (0..model.coordinates.len()).map(|j| 0.2 * s - 0.1 * j as f64).collect();
                Member { params, q0, qd0 }
            })
            .collect()
    }

    /// An output larger than the limit, or more threads than a sane multiple of the cores,
    /// is refused before anything runs or is allocated, naming the limit.
    #[test]
    fn oversized_ensembles_are_refused_before_they_run() {
        let model = generated::three_body::model();
        let members = members(&model, 3);
        let times = [0.0, 0.1, 0.2];
        let states = model.formulation(FormulationKind::Kane).unwrap().states();
        let values = 9 * states;
        let e =
            ensemble(&model, FormulationKind::Kane, &members, &times, &Settings::tight(0.2), None, values - 1, &|| {}, &AtomicBool::new(false)).unwrap_err();
        assert!(matches!(e, EnsembleError::TooLarge { values: v, .. } if v == values as u128), "{e}");
        assert!(e.to_string().contains(&format!("3 members x 3 times x {states} states = {values} numbers")) && e.to_string().contains("max_values"), "{e}");
        ensemble(&model, FormulationKind::Kane, &members, &times, &Settings::tight(0.2), None, values, &|| {}, &AtomicBool::new(false)).unwrap();
        // A million members of a thousand times: refused at once, nothing allocated.
        let many = vec![members[0].clone(); 1_000_000];
        let long: Vec<f64> = (0..1000).map(|i| i as f64).collect();
        let e = ensemble(&model, FormulationKind::Kane, &many, &long, &Settings::tight(999.0), None, DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false));
        assert!(matches!(e, Err(EnsembleError::TooLarge { .. })));
        for threads in [0, 10_000, 1_000_000] {
            let e = ensemble(
                &model,
                FormulationKind::Kane,
                &members,
                &times,
                &Settings::tight(0.2),
                Some(threads),
                DEFAULT_MAX_VALUES,
                &|| {},
                &AtomicBool::new(false),
            );
            assert!(matches!(e, Err(EnsembleError::Threads { .. })), "{threads}: {e:?}");
        }
    }

    /// Each member of a parallel ensemble is, to the bit, its run alone; and the result does
    /// not depend on the number of threads.
    #[test]
    fn members_equal_their_sequential_runs() {
        let model = generated::three_body::model();
        let times: Vec<f64> = (0..=20).map(|i| 0.05 * i as f64).collect();
        let settings = Settings::tight(1.0);
        let members = members(&model, 12);
        for kind in [FormulationKind::Kane, FormulationKind::ReducedVolterra] {
            let done = std::sync::atomic::AtomicUsize::new(0);
            let count = || {
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            };
            let parallel = ensemble(&model, kind, &members, &times, &settings, Some(2), DEFAULT_MAX_VALUES, &count, &AtomicBool::new(false)).unwrap();
            assert_eq!(done.into_inner(), members.len());
            let one_thread = ensemble(&model, kind, &members, &times, &settings, Some(1), DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false)).unwrap();
            assert_eq!(parallel, one_thread);
            for (k, member) in members.iter().enumerate() {
                let (sys, y0) = System::start(&model, kind, member.params.clone(), &member.q0, &member.qd0).unwrap();
                let alone = run(&sys, &y0, &times, &Settings { time_independent: true, ..settings }, &mut |_| {}).unwrap().solution;
                let alone: Vec<f64> = alone.states.iter().flatten().copied().collect();
                assert_eq!(parallel.member(k), &alone[..], "member {k}, {kind}");
            }
            // The members differ: the test would notice a member run with another's values.
            assert_ne!(parallel.member(0), parallel.member(1));
            assert_eq!(parallel.reached, vec![times.len(); members.len()]);
        }
    }

    /// Each member carries its own stiffness verdict: the stiff pendulum at k = 1e8 looks
    /// stiff to DOP853 early, the same pendulum on a soft spring (k = 100) does not.
    #[test]
    fn each_member_says_whether_it_looked_stiff() {
        let model = generated::stiff_pendulum::model();
        let k = model.parameter_index("k").unwrap();
        let mut calm = Member { params: model.default_params.clone(), q0: vec![0.3; model.coordinates.len()], qd0: vec![0.0; model.coordinates.len()] };
        let mut stiff = calm.clone();
        calm.params[k] = 100.0;
        stiff.params[k] = 1e8;
        let times = [0.0, 0.1, 0.2];
        let settings = Settings { rtol: 1e-4, atol: 1e-4, ..Settings::tight(0.2) };
        let runs =
            ensemble(&model, FormulationKind::Kane, &[calm, stiff], &times, &settings, Some(2), DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!(runs.stiff_at[0], None);
        assert!(runs.stiff_at[1].is_some_and(|t| t < 0.05), "{:?}", runs.stiff_at);
    }

    /// A member with the wrong number of values is named; so is one whose run fails.
    #[test]
    fn the_failing_member_is_named() {
        let model = generated::three_body::model();
        let mut members = members(&model, 5);
        members[3].q0.pop();
        let e =
            ensemble(&model, FormulationKind::Kane, &members, &[0.0, 0.1], &Settings::tight(0.1), None, DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false))
                .unwrap_err();
        assert!(matches!(e, EnsembleError::Shape { member: 3, what: "q0", .. }), "{e}");
        let e = ensemble(
            &model,
            FormulationKind::Kane,
            &members[..2],
            &[0.0, 0.0],
            &Settings::tight(0.1),
            None,
            DEFAULT_MAX_VALUES,
            &|| {},
            &AtomicBool::new(false),
        )
        .unwrap_err();
        assert!(matches!(e, EnsembleError::Times), "{e}");
    }

    /// Setting `stop` ends the ensemble with `Interrupted`: here after the first member, on
    /// one thread, so the others never run; a member given a stop already set does not start;
    /// and a run stops at the right-hand side its callback breaks.
    #[test]
    fn a_stopped_ensemble_is_interrupted() {
        let model = generated::three_body::model();
        let times: Vec<f64> = (0..=20).map(|i| 0.05 * i as f64).collect();
        let members = members(&model, 6);
        let stop = AtomicBool::new(false);
        let done = std::sync::atomic::AtomicUsize::new(0);
        let stop_after_first = || {
            done.fetch_add(1, Ordering::Relaxed);
            stop.store(true, Ordering::Relaxed);
        };
        let e = ensemble(&model, FormulationKind::Kane, &members, &times, &Settings::tight(1.0), Some(1), DEFAULT_MAX_VALUES, &stop_after_first, &stop)
            .unwrap_err();
        assert!(matches!(e, EnsembleError::Interrupted), "{e}");
        // The same ensemble without the stop runs to the end.
        assert!(
            ensemble(&model, FormulationKind::Kane, &members, &times, &Settings::tight(1.0), Some(1), DEFAULT_MAX_VALUES, &|| {}, &AtomicBool::new(false))
                .is_ok()
        );
        let (sys, y0) = System::start(&model, FormulationKind::Kane, members[0].params.clone(), &members[0].q0, &members[0].qd0).unwrap();
        let running = run_member(&model, FormulationKind::Kane, &members[0], 0, &times, &Settings::tight(1.0), &AtomicBool::new(true));
        assert!(matches!(running, Err(EnsembleError::Interrupted)));
        let mut calls = 0;
        let err = run_interruptible(&sys, &y0, &times, &Settings::tight(1.0), &mut |_| {
            calls += 1;
            if calls > 50 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        })
        .unwrap_err();
        assert_eq!(err.reason, Reason::Interrupted);
        assert!(err.t > 0.0 && err.t < 1.0, "{err}");
        assert_eq!(err.state.len(), y0.len());
    }

    /// A terminal event stops its member: the rows after it are NaN and `reached` says so,
    /// while a slower member runs to the end.
    #[test]
    fn a_stopped_member_reports_where() {
        // The ball reaches the wall at x = 5 at t = 5 / x'(0): 2.27 for the first, 5 for the
        // second, after the run's 4 s (its bounces pile up only at 8.6 s).
        let model = generated::bouncing_ball::model();
        let member = |speed: f64| Member { params: model.default_params.clone(), q0: vec![0.0, 1.0], qd0: vec![speed, 0.0] };
        let times: Vec<f64> = (0..=8).map(|i| 0.5 * f64::from(i)).collect();
        let runs = ensemble(
            &model,
            FormulationKind::Kane,
            &[member(2.2), member(1.0)],
            &times,
            &Settings::tight(4.0),
            None,
            DEFAULT_MAX_VALUES,
            &|| {},
            &AtomicBool::new(false),
        )
        .unwrap();
        assert_eq!(runs.reached, [5, 9]);
        let first = runs.member(0);
        assert!(first[..5 * runs.states].iter().all(|x| x.is_finite()));
        assert!(first[5 * runs.states..].iter().all(|x| x.is_nan()));
        assert!(runs.member(1).iter().all(|x| x.is_finite()));
        // x = x'(0) t before the wall (x is ignorable: no force along it), at t = 2.
        assert!((first[4 * runs.states] - 4.4).abs() < 1e-9, "{}", first[4 * runs.states]);
    }
}
