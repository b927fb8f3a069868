//! The compiled route end to end: a committed model's emitted module built by rustc into a
//! library, loaded, its numbers and failures equal to the in-process evaluation's; the cache
//! reused by content; concurrent builds of one key built once; a swapped library refused.

use std::path::Path;

/// The model's emitted module and its in-process evaluation (the description, and the numbers to
/// compare with).
fn generated(file: &str) -> (String, seam::Model) {
    let model = generator::model::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("../models").join(file)).unwrap();
    let options = generator::emit::Options { tapes: true, ..generator::emit::Options::from_model(&model) };
    let g = generator::generate(&model, &options).unwrap();
    (g.code, generator::eval::model::Evaluated::model(g.program.unwrap()))
}

fn close(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    for (x, y) in a.iter().zip(b) {
        assert!((x - y).abs() <= 1e-13 * x.abs().max(y.abs()).max(1.0), "{what}: {a:?} vs {b:?}");
    }
}

/// Every function of scene 2, through the library, equals the in-process evaluation (which the
/// workspace tests hold equal to the compiled module); failures cross as the same values.
#[test]
fn the_library_computes_what_the_module_computes() {
    let cache = tempfile::tempdir().unwrap();
    let (code, evaluated) = generated("three_body.ron");
    let mut told = 0;
    let library = native::build(&code, cache.path(), &mut |_| told += 1).unwrap();
    assert!(library.built());
    assert_eq!(told, 1);
    let compiled = library.model(evaluated.clone()).unwrap();
    assert_eq!(library.formulations(), ["lagrange", "maggi", "kane", "reduced_volterra"]);
    let (q0, qd0) = evaluated.initial.clone().unwrap();
    let params = evaluated.default_params.clone();
    let m = q0.len();
    for (fe, fc) in evaluated.formulations.iter().zip(&compiled.formulations) {
        let name = fe.name();
        let (mut ye, mut ge) = (vec![0.0; fe.states()], vec![0.0; evaluated.ignorable.len()]);
        let (mut yc, mut gc) = (ye.clone(), ge.clone());
        fe.initial_state(0.0, &q0, &qd0, &params, &mut ye, &mut ge).unwrap();
        fc.initial_state(0.0, &q0, &qd0, &params, &mut yc, &mut gc).unwrap();
        close(&ye, &yc, name);
        close(&ge, &gc, name);
        let (mut de, mut dc) = (vec![0.0; ye.len()], vec![0.0; ye.len()]);
        fe.rhs(0.3, &ye, &params, &ge, &mut de).unwrap();
        fc.rhs(0.3, &ye, &params, &ge, &mut dc).unwrap();
        close(&de, &dc, name);
        let n = fe.matrix_size;
        let (mut me, mut mc) = (vec![0.0; n * n], vec![0.0; n * n]);
        fe.matrix(0.3, &ye, &params, &ge, &mut me).unwrap();
        fc.matrix(0.3, &ye, &params, &ge, &mut mc).unwrap();
        close(&me, &mc, name);
        let (mut qa, mut va, mut qb, mut vb) = (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        fe.velocities(0.3, &ye, &params, &ge, &mut qa, &mut va).unwrap();
        fc.velocities(0.3, &ye, &params, &ge, &mut qb, &mut vb).unwrap();
        close(&qa, &qb, name);
        close(&va, &vb, name);
        let margins = (fe.singular_margin(0.3, &ye, &params, &ge).unwrap(), fc.singular_margin(0.3, &ye, &params, &ge).unwrap());
        assert!(margins.0 == margins.1 || (margins.0 - margins.1).abs() <= 1e-13 * margins.0.abs(), "{name}: {margins:?}");
        // A short state is the same error, with the same argument name.
        let short = (fe.rhs(0.3, &ye[1..], &params, &ge, &mut de), fc.rhs(0.3, &yc[1..], &params, &gc, &mut dc));
        assert!(short.0.is_err());
        assert_eq!(short.0, short.1, "{name}");
        // So is a function the module was emitted without.
        assert_eq!(fe.jacobian(0.3, &ye, &params, &ge, &mut de, &mut []), fc.jacobian(0.3, &ye, &params, &ge, &mut dc, &mut []));
    }
    for (k, point) in [seam::Model::energy, seam::Model::momenta, seam::Model::constraint_residuals].into_iter().enumerate() {
        let size = [1, evaluated.ignorable.len(), evaluated.constraints.len()][k];
        let (mut a, mut b) = (vec![0.0; size], vec![0.0; size]);
        point(&evaluated, 0.3, &q0, &qd0, &params, &mut a).unwrap();
        point(&compiled, 0.3, &q0, &qd0, &params, &mut b).unwrap();
        close(&a, &b, "model function");
    }
}

/// A failure that carries text (a singular configuration, a violated constraint) crosses with it.
#[test]
fn failures_cross_with_their_text() {
    let cache = tempfile::tempdir().unwrap();
    let (code, evaluated) = generated("rolling_disk.ron");
    let compiled = native::build(&code, cache.path(), &mut |_| {}).unwrap().model(evaluated.clone()).unwrap();
    let (q0, mut qd0) = evaluated.initial.clone().unwrap();
    qd0.iter_mut().for_each(|v| *v += 0.7);
    let params = evaluated.default_params.clone();
    for (fe, fc) in evaluated.formulations.iter().zip(&compiled.formulations) {
        let (mut y, mut g) = (vec![0.0; fe.states()], vec![0.0; evaluated.ignorable.len()]);
        let a = fe.initial_state(0.0, &q0, &qd0, &params, &mut y, &mut g);
        let b = fc.initial_state(0.0, &q0, &qd0, &params, &mut y, &mut g);
        assert!(matches!(a, Err(seam::Failure::ConstraintViolated { .. })), "{a:?}");
        assert_eq!(a, b);
    }
    // A matrix the numerical solve finds singular (every mass and inertia zero): the matrix's
    // name and the pivot's column cross.
    let (q0, qd0) = evaluated.initial.clone().unwrap();
    let massless: Vec<f64> = evaluated
        .parameter_names
        .iter()
        .zip(&params)
        .map(|(n, v)| if n.starts_with('m') || n.starts_with('I') || n.starts_with('J') { 0.0 } else { *v })
        .collect();
    let mut solved = 0;
    for (fe, fc) in evaluated.formulations.iter().zip(&compiled.formulations) {
        let (mut y, mut g) = (vec![0.0; fe.states()], vec![0.0; evaluated.ignorable.len()]);
        fe.initial_state(0.0, &q0, &qd0, &params, &mut y, &mut g).unwrap();
        let mut d = vec![0.0; y.len()];
        let a = fe.rhs(0.0, &y, &massless, &g, &mut d);
        let b = fc.rhs(0.0, &y, &massless, &g, &mut d);
        assert_eq!(a, b, "{}", fe.name());
        if let Err(seam::Failure::SingularMatrix { matrix, .. }) = &a {
            assert!(!matrix.is_empty(), "{}", fe.name());
            assert!(a.as_ref().unwrap_err().to_string().contains("has no usable pivot in column"), "{a:?}");
            solved += 1;
        }
    }
    assert!(solved > 0, "no formulation's solve refused the massless disk");
}

/// The second build of the same module loads the cached library without building; another
/// module gets another library.
#[test]
fn the_cache_is_keyed_by_content() {
    let cache = tempfile::tempdir().unwrap();
    let (spring, _) = generated("spring_cart.ron");
    let first = native::build(&spring, cache.path(), &mut |_| {}).unwrap();
    let modified = std::fs::metadata(first.path()).unwrap().modified().unwrap();
    let again = native::build(&spring, cache.path(), &mut |_| panic!("built again")).unwrap();
    assert!(!again.built());
    assert_eq!(first.path(), again.path());
    assert_eq!(std::fs::metadata(again.path()).unwrap().modified().unwrap(), modified);
    let other = native::build(&spring.replacen("spring_cart", "spring_cart_2", 1), cache.path(), &mut |_| {}).unwrap();
    assert!(other.built());
    assert_ne!(other.path(), first.path());
}

/// Three builds of one key at once: one builds, the others wait for its lock and load the result;
/// no temporary folder is left behind.
#[test]
fn concurrent_builds_of_one_key_build_once() {
    let cache = tempfile::tempdir().unwrap();
    let (spring, _) = generated("spring_cart.ron");
    let built: Vec<bool> = std::thread::scope(|s| {
        let runs: Vec<_> = (0..3).map(|_| s.spawn(|| native::build(&spring, cache.path(), &mut |_| {}).unwrap().built())).collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    assert_eq!(built.iter().filter(|b| **b).count(), 1, "{built:?}");
    let leftovers: Vec<_> =
        std::fs::read_dir(cache.path()).unwrap().map(|e| e.unwrap().file_name()).filter(|n| n.to_string_lossy().starts_with(".build-")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// A library swapped in the cache (another model's, copied over it) or truncated (a full disk,
/// a killed copy: it ended the tool with SIGBUS) does not match the digest kept beside it: it
/// is never loaded, and is built again; a library given another model's description is refused.
#[test]
fn a_swapped_or_truncated_library_is_built_again() {
    let cache = tempfile::tempdir().unwrap();
    let (spring, spring_model) = generated("spring_cart.ron");
    let (cart, _) = generated("cart_pendulum.ron");
    let a = native::build(&spring, cache.path(), &mut |_| {}).unwrap();
    let b = native::build(&cart, cache.path(), &mut |_| {}).unwrap();
    let (a_path, b_path) = (a.path().to_path_buf(), b.path().to_path_buf());
    drop(a);
    let mut fewer = spring_model.clone();
    fewer.formulations.truncate(1);
    let e = b.model(fewer).expect_err("refused").to_string();
    assert!(e.contains("its formulations are"), "{e}");
    drop(b);
    std::fs::copy(&b_path, &a_path).unwrap();
    let again = native::build(&spring, cache.path(), &mut |_| {}).unwrap();
    assert!(again.built(), "the swapped library is built again");
    let model = again.model(spring_model.clone()).unwrap();
    assert_eq!(model.formulations.len(), spring_model.formulations.len());
    drop((again, model));
    let length = std::fs::metadata(&a_path).unwrap().len();
    std::fs::OpenOptions::new().write(true).open(&a_path).unwrap().set_len(length / 3).unwrap();
    let again = native::build(&spring, cache.path(), &mut |_| {}).unwrap();
    assert!(again.built(), "the truncated library is built again");
    assert_eq!(std::fs::metadata(&a_path).unwrap().len(), length);
}

/// A rustc killed midway (out of memory, Ctrl-C) is said to be so, not reported as a fault of
/// multibody; the folder it left is gone after the next build of the key.
#[cfg(unix)]
#[test]
fn a_killed_rustc_is_named() {
    use std::os::unix::fs::PermissionsExt;
    let cache = tempfile::tempdir().unwrap();
    let (spring, _) = generated("spring_cart.ron");
    let killer = cache.path().join("killed-rustc");
    std::fs::write(&killer, "#!/bin/sh\nkill -9 $$\n").unwrap();
    std::fs::set_permissions(&killer, std::fs::Permissions::from_mode(0o755)).unwrap();
    let folder = cache.path().join("cache");
    let e = native::build_with(&spring, &folder, &killer, &mut |_| {}).err().expect("refused").to_string();
    assert!(e.contains("rustc was killed (signal 9)") && !e.contains("fault of multibody"), "{e}");
    let leftovers = |dir: &Path| std::fs::read_dir(dir).unwrap().filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with(".build-")).count();
    // A build killed with the tool (kill -9) leaves its folder: the next build removes it.
    let key = native::key(&spring);
    std::fs::create_dir(folder.join(format!("{}stale", native::cache::build_prefix(&key)))).unwrap();
    assert_eq!(leftovers(&folder), 1);
    native::build(&spring, &folder, &mut |_| {}).unwrap();
    assert_eq!(leftovers(&folder), 0);
}

/// Without rustc, the first build says what is needed and how to do without it.
#[test]
fn a_missing_rustc_is_named() {
    let cache = tempfile::tempdir().unwrap();
    let (spring, _) = generated("spring_cart.ron");
    let e = native::build_with(&spring, cache.path(), Path::new("/nonexistent/rustc"), &mut |_| {}).err().expect("refused").to_string();
    assert!(e.contains("needs rustc") && e.contains("/nonexistent/rustc") && e.contains("leave out --compiled"), "{e}");
}
