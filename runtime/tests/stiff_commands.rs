//! The stiff integrator is selectable where the other integrators are: `compare --method
//! ros23` and `sweep --methods ...,ros23`, on the committed stiff extreme.

use clap::Parser;
use runtime::cli::{CompareArgs, SweepArgs, compare_options, sweep_command};
use runtime::compare::run_with;
use runtime::integrate::Method;

#[test]
fn compare_runs_the_rosenbrock_method_with_the_exact_jacobian() {
    let model = generated::find("stiff_pendulum").unwrap();
    let args = CompareArgs::parse_from(["compare", "stiff_pendulum", "--method", "ros23", "--rtol", "1e-4", "--atol", "1e-4", "--repeats", "1"]);
    let options = compare_options(&model, &args).unwrap();
    assert_eq!(options.settings.method, Method::Rosenbrock23);
    let run = run_with(&model, "kane", &options.settings, 1, options.drift).unwrap();
    assert_eq!(run.record.integrator, "ROS23");
    assert!(run.record.steps > 0 && run.record.steps < 20_000, "{:?}", run.record.steps);
    // The exact Jacobian saves the differences: three right-hand sides a step and no more.
    assert!(run.record.rhs_calls <= 3 * (run.record.steps + run.record.rejected) + 10, "{} calls for {} steps", run.record.rhs_calls, run.record.steps);
}

#[test]
fn sweep_runs_the_integrators_it_is_given() {
    let model = generated::find("stiff_pendulum").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let args = SweepArgs::parse_from([
        "sweep",
        "stiff_pendulum",
        "--quick",
        "--repeats",
        "1",
        "--formulations",
        "kane",
        "--methods",
        "dopri5,ros23",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    sweep_command(&model, &args).unwrap();
    let csv = std::fs::read_to_string(dir.path().join("stiff_pendulum_work_precision.csv")).unwrap();
    let integrators: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap()).collect();
    // Three tolerances each, no RK4 (not asked for).
    assert_eq!(integrators, ["DOPRI5", "DOPRI5", "DOPRI5", "ROS23", "ROS23", "ROS23"], "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.ends_with(',')), "no run failed: {csv}");
}
