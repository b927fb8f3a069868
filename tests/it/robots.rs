//! Robots read from URDF (the issue "Robots"), on small files written for the tests
//! (`tests/fixtures/urdf/`): a branching tree with fixed, prismatic and tilted joints, on a fixed
//! and on a floating base. Their properties: the four formulations agree, Lagrange's equations
//! hold at random states, the energy and the base's momenta are conserved without gravity, a
//! tilted axis meets its closed form, fixed links are merged exactly; and every refusal is
//! located in the XML.

use crate::common::{check_formulations_agree, multibody, ok};
use generator::model::{Base, LimitAction, UrdfOptions, urdf_model_file as model_file};
use generator::model::{from_source, to_ron};
use runtime::integrate::Settings;
use runtime::system::System;
use seam::FormulationKind;

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/urdf/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn robot(name: &str, options: &UrdfOptions) -> generator::model::Model {
    generator::model::source_with(fixture(name).as_ref(), options).unwrap().model().unwrap()
}

fn floating(gravity: [f64; 3]) -> UrdfOptions {
    UrdfOptions { base: Base::Floating, gravity, limits: LimitAction::Report }
}

/// On a fixed base, the tree's four formulations give the same accelerations, which satisfy
/// Lagrange's equations derived from T, at random states; coordinates are the joints, in the
/// tree's breadth-first order, the fixed `neck` none.
#[test]
fn a_fixed_tree_obeys_lagrange_in_every_formulation() {
    let model = robot("tree.urdf", &UrdfOptions::default());
    let names: Vec<String> = model.coordinates.iter().map(|c| c.name()).collect();
    assert_eq!(names, ["waist", "left_shoulder", "right_shoulder", "left_elbow", "right_wrist"]);
    let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    check_formulations_agree("tree", &d, &model, 4, 42);
}

/// The head, fixed to the torso, is one body with it: their masses add, the centre of mass is
/// their weighted mean, and the inertia about it is each one's moved there (parallel axes),
/// in the torso's frame.
#[test]
fn fixed_links_merge_exactly() {
    let xml = std::fs::read_to_string(fixture("tree.urdf")).unwrap();
    let def = model_file("tree.urdf", &xml, &UrdfOptions::default()).unwrap();
    assert_eq!(def.parameters["mass_torso"], 4.0);
    let torso = def.bodies.iter().find(|b| b.name == "torso").unwrap();
    assert!(def.bodies.iter().all(|b| b.name != "head"));
    let com: Vec<f64> = torso.com.as_ref().unwrap().iter().map(|x| x.parse().unwrap()).collect();
    // The torso's own centre of mass (0, 0, 0.3); the head's (0.02, 0, 0.1) in a frame at
    // (0, 0, 0.55) turned by 0.4 about z: (0.02 cos 0.4, 0.02 sin 0.4, 0.65).
    let head = [0.02 * 0.4f64.cos(), 0.02 * 0.4f64.sin(), 0.65];
    let want = [(3.0 * 0.0 + head[0]) / 4.0, head[1] / 4.0, (3.0 * 0.3 + head[2]) / 4.0];
    for k in 0..3 {
        assert!((com[k] - want[k]).abs() < 1e-14, "{com:?} against {want:?}");
    }
    // Izz about the combined centre: the torso's (its tensor turned by roll 0.1 about x) and the
    // head's 0.004, each shifted by m d^2 across the plane.
    let generator::model::InertiaDef::Matrix(rows) = &torso.inertia else { panic!("a matrix") };
    let izz: f64 = rows[2][2].parse().unwrap();
    let (c, s) = (0.1f64.cos(), 0.1f64.sin());
    let torso_zz = s * s * 0.10 + c * c * 0.04 + 2.0 * s * c * 0.001;
    let d2 = |p: [f64; 3]| (p[0] - want[0]).powi(2) + (p[1] - want[1]).powi(2);
    let expected = torso_zz + 3.0 * d2([0.0, 0.0, 0.3]) + 0.004 + 1.0 * d2(head);
    assert!((izz - expected).abs() < 1e-14, "{izz} against {expected}");
}

/// A rod turning about the tilted axis (0.6, 0, 0.8) through the origin, its centre 0.5 from the
/// axis along y: `z = 0.3 sin(q)`, so `I_a q'' = -0.3 m g cos(q)` with
/// `I_a = a^T I a + m 0.25`. Every formulation gives it.
#[test]
fn a_tilted_axis_meets_its_closed_form() {
    let model = robot("tilted.urdf", &UrdfOptions::default());
    let seam = load::evaluate(&model, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
    let (m, g) = (2.0, 9.81);
    let ia = 0.36 * 0.02 + 0.64 * 0.01 + m * 0.25;
    for q in [0.0, 0.4, -1.3] {
        let expected = -0.3 * m * g * f64::cos(q) / ia;
        for kind in FormulationKind::ALL {
            let (sys, y) = System::start(&seam, kind, seam.default_params.clone(), &[q], &[0.7]).unwrap();
            let mut dy = vec![0.0; y.len()];
            sys.rhs(0.0, &y, &mut dy).unwrap();
            assert!((dy[1] - expected).abs() < 1e-12, "{kind} at q = {q}: q'' = {} against {expected}", dy[1]);
        }
    }
}

/// On a floating base without gravity the robot keeps its energy and its linear momentum
/// (the base's three translations are ignorable): the reduced method to round-off, every
/// formulation to the tolerance; the four agree on the motion.
#[test]
fn a_floating_tree_keeps_energy_and_momentum() {
    let model = robot("tree.urdf", &floating([0.0; 3]));
    let names: Vec<String> = model.coordinates.iter().take(7).map(|c| c.name()).collect();
    assert_eq!(names, ["base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz"]);
    keeps_energy_and_momentum(
        &model,
        &[("waist", 1.0), ("left_shoulder", 0.5), ("left_elbow", -0.7), ("right_wrist", 0.05), ("base_x", 0.2), ("base_qz", 0.3)],
    );
}

/// A serial chain of 8 joints whose origins turn by 0.1 rad (dense rotations, long decimals),
/// on a floating base without gravity, as the tree above. Its derivation's pivot checks once
/// walked the DAG as a tree: a 20-joint one did not derive in 5 minutes.
#[test]
fn a_floating_snake_with_turned_origins_keeps_energy_and_momentum() {
    let model = robot("snake.urdf", &floating([0.0; 3]));
    assert_eq!(model.coordinates.len(), 7 + 8);
    keeps_energy_and_momentum(&model, &[("j1", 0.8), ("j2", -0.5), ("j4", 0.6), ("j7", -0.4), ("j8", 0.3), ("base_y", 0.1), ("base_qx", 0.2)]);
}

/// `model` run from its initial state with the rates `rates` in every formulation: energy kept
/// to 1e-9, the ignorable momenta to round-off (reduced) or the tolerance, the unit norm kept,
/// the four ending at the same configuration.
fn keeps_energy_and_momentum(model: &generator::model::Model, rates: &[(&str, f64)]) {
    let seam = load::evaluate(model, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
    assert_eq!(seam.ignorable.len(), 3);
    let (q0, mut qd0) = seam.initial.clone().unwrap();
    for (name, v) in rates {
        qd0[seam.coordinate_index(name).unwrap()] = *v;
    }
    let times: Vec<f64> = (0..=20).map(|i| 0.05 * i as f64).collect();
    let settings = Settings { rtol: 1e-11, atol: 1e-11, ..Settings::tight(1.0) };
    let mut ends = Vec::new();
    for kind in FormulationKind::ALL {
        let (sys, y0) = System::start(&seam, kind, seam.default_params.clone(), &q0, &qd0).unwrap();
        let run = runtime::trajectory::simulate(&sys, &y0, &times, &settings, &mut |_| {}).unwrap();
        let inv = &run.invariants;
        let worst = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(worst(&inv.energy_error) < 1e-9 * inv.energy0.abs(), "{kind}: energy {:e}", worst(&inv.energy_error));
        let momentum_bound = if kind == FormulationKind::ReducedVolterra { 1e-13 } else { 1e-8 };
        for (k, drift) in inv.momentum_error.iter().enumerate() {
            assert!(worst(drift) < momentum_bound * (1.0 + inv.momentum0[k].abs()), "{kind}: momentum {k} drifts {:e}", worst(drift));
        }
        assert!(worst(&inv.position_constraint) < 1e-9, "{kind}: the unit norm drifts {:e}", worst(&inv.position_constraint));
        ends.push(inv.coordinates.last().unwrap().clone());
    }
    for end in &ends[1..] {
        for (a, b) in end.iter().zip(&ends[0]) {
            assert!((a - b).abs() < 1e-7, "{end:?} against {:?}", ends[0]);
        }
    }
}

/// With gravity along -z, the floating base's horizontal translations stay ignorable and the
/// vertical one does not; the reduced method solves two equations fewer than Kane's.
#[test]
fn gravity_decides_the_ignorable_translations() {
    let model = robot("tree.urdf", &floating([0.0, 0.0, -9.81]));
    let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    let names: Vec<String> = d.ignorable.iter().map(|&j| model.coordinates[j].name()).collect();
    assert_eq!(names, ["base_x", "base_y"]);
    let kane = d.equations("kane").unwrap().equations;
    assert_eq!(d.equations("reduced_volterra").unwrap().equations, kane - 2);
}

/// A RON model that includes the URDF and adds to it: a payload on the right hand, a spring on
/// the waist, a torque input per shoulder; its own coordinates and rates follow the robot's.
#[test]
fn a_ron_model_includes_a_urdf_and_adds_to_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixture("tree.urdf"), dir.path().join("tree.urdf")).unwrap();
    let ron = r#"Model(
        name: "tree_with_payload",
        urdf: Urdf(file: "tree.urdf", base: Fixed),
        parameters: { "m_payload": 0.5, "k": 3.0 },
        inputs: { "tau_left": 0.0, "tau_right": 0.0 },
        coordinates: ["slide"],
        frames: [Frame(name: "payload", parent: "right_hand", translation: ["slide", "-0.05", "0"])],
        bodies: [Body(name: "payload", frame: "payload", mass: "m_payload", inertia: PointMass)],
        forces: [
            Potential(name: "waist spring", expr: "k*waist^2/2 + 10*slide^2"),
            Generalized(name: "motors", components: {"left_shoulder": "tau_left", "right_shoulder": "tau_right"}),
        ],
        initial: Initial(q: {"slide": "0.01"}, qdot: {}),
    )"#;
    let path = dir.path().join("with_payload.ron");
    std::fs::write(&path, ron).unwrap();
    let model = generator::model::load(&path).unwrap();
    let names: Vec<String> = model.coordinates.iter().map(|c| c.name()).collect();
    assert_eq!(names, ["waist", "left_shoulder", "right_shoulder", "left_elbow", "right_wrist", "slide"]);
    assert_eq!(model.inputs.len(), 2);
    let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    check_formulations_agree("tree_with_payload", &d, &model, 3, 7);
    // The command line runs it as it runs any model.
    let text = ok(&multibody(dir.path(), &["compare", "with_payload.ron", "--t-end", "0.2", "--repeats", "1"]));
    assert!(text.contains("| reduced_volterra |"), "{text}");
}

/// The Rust builder includes a URDF as a RON model does, and adds to it.
#[test]
fn the_builder_includes_a_urdf_and_adds_to_it() {
    use generator::model::builder::{Body, Frame, ModelBuilder};
    let model = ModelBuilder::new("tree_with_payload")
        .urdf(fixture("tree.urdf"), &UrdfOptions::default())
        .parameter("m_payload", 0.5)
        .coordinate("slide")
        .frame(Frame::new("payload", "right_hand").translation(["slide", "-0.05", "0"]))
        .body(Body::new("payload", "payload", "m_payload"))
        .build()
        .unwrap();
    let names: Vec<String> = model.coordinates.iter().map(|c| c.name()).collect();
    assert_eq!(names, ["waist", "left_shoulder", "right_shoulder", "left_elbow", "right_wrist", "slide"]);
    let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    check_formulations_agree("tree_with_payload (builder)", &d, &model, 2, 11);
    // A URDF that is not there is named in the error.
    let err = ModelBuilder::new("missing").urdf("/nonexistent/robot.urdf", &UrdfOptions::default()).build().unwrap_err();
    assert!(err.to_string().contains("/nonexistent/robot.urdf"), "{err}");
}

/// Each link's visuals become its body's drawn shapes, placed in the body's frame: the torso's
/// box; the head's sphere, merged with the torso, where the fixed neck puts it; the upper arm's
/// cylinder turned a quarter about x; the hand's STL mesh (millimetres scaled to metres); the
/// right upper arm's COLLADA mesh (in millimetres by its `<unit>`, placed by its node); the
/// forearm's COLLADA mesh, whose file is not there, not drawn, and its OBJ mesh beside it, drawn;
/// the base's cylinder, on a fixed base, as scenery.
#[test]
fn visuals_become_shapes_in_their_body_frames() {
    let model = robot("tree.urdf", &UrdfOptions::default());
    let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
    let poser = generator::pose::Poser::new(&model, &params).unwrap();
    let body = |name: &str| poser.bodies.iter().find(|b| b.name == name).unwrap().shapes.clone();
    let close = |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    let identity = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let torso = body("torso");
    assert_eq!(torso.iter().map(|s| s.solid).collect::<Vec<_>>(), ["box", "sphere"]);
    assert!(close(&torso[0].sizes, &[0.2, 0.3, 0.5]) && close(&torso[0].origin, &[0.0, 0.0, 0.3]) && close(&torso[0].rotation, &identity), "{torso:?}");
    // The neck: (0, 0, 0.55) turned by 0.4 about z; the sphere at (0.02, 0, 0.1) in the head.
    let head = [0.02 * 0.4f64.cos(), 0.02 * 0.4f64.sin(), 0.65];
    assert!(close(&torso[1].sizes, &[0.08]) && close(&torso[1].origin, &head), "{torso:?}");
    let arm = body("left_upper");
    assert_eq!(arm.len(), 1);
    assert!(arm[0].solid == "cylinder" && close(&arm[0].sizes, &[0.04, 0.3]) && close(&arm[0].origin, &[0.0, 0.15, 0.0]), "{arm:?}");
    // Roll pi/2 about x: its axis (the third column) along -y, its y along z.
    let r = arm[0].rotation;
    assert!(close(&[r[2], r[5], r[8]], &[0.0, -1.0, 0.0]) && close(&[r[1], r[4], r[7]], &[0.0, 0.0, 1.0]), "{r:?}");
    // The STL's two triangles, in millimetres: the mesh scaled by a thousandth, at the visual's
    // origin (0, -0.05, 0).
    let hand = body("right_hand");
    assert!(hand[0].solid == "mesh" && close(&hand[0].sizes, &[0.001; 3]) && close(&hand[0].origin, &[0.0, -0.05, 0.0]), "{hand:?}");
    let mesh = hand[0].mesh.as_ref().unwrap();
    assert_eq!(mesh.vertices, [[-20.0, -50.0, -10.0], [20.0, -50.0, -10.0], [20.0, 10.0, 10.0], [-20.0, 10.0, 10.0]]);
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    // COLLADA: the triangle in millimetres, moved 150 of them along -y by its node, in metres;
    // its Y_UP not applied.
    let upper = body("right_upper");
    assert!(upper.len() == 1 && upper[0].solid == "mesh" && close(&upper[0].sizes, &[1.0; 3]), "{upper:?}");
    let mesh = upper[0].mesh.as_ref().unwrap();
    let expected = [[-0.02, -0.15, 0.0], [0.02, -0.15, 0.0], [0.0, -0.15, 0.04]];
    assert!(mesh.vertices.len() == 3 && mesh.vertices.iter().zip(expected).all(|(v, e)| close(v, &e)), "{:?}", mesh.vertices);
    // OBJ: the pyramid's quad base and four sides, six triangles; the missing COLLADA file
    // beside it is not drawn.
    let lower = body("left_lower");
    assert!(lower.len() == 1 && lower[0].solid == "mesh", "{lower:?}");
    let mesh = lower[0].mesh.as_ref().unwrap();
    assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (5, 6));
    // Mesh files are read in single precision (`mesh-loader`'s f32): 0.02 is 0.0199999996.
    let single = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-7);
    assert!(single(&mesh.bounds().1, &[0.02, 0.25, 0.02]) && single(&mesh.bounds().0, &[-0.02, 0.0, -0.02]), "{:?}", mesh.bounds());
    // On a fixed base, the base link's cylinder is scenery, fixed to the world where it is.
    assert!(poser.scenery.len() == 1 && poser.scenery[0].solid == "cylinder" && close(&poser.scenery[0].origin, &[0.0, 0.0, 0.05]), "{:?}", poser.scenery);
    // On a floating base, it is the base's own shape, and there is no scenery.
    let floating_model = robot("tree.urdf", &floating([0.0, 0.0, -9.81]));
    let floating_poser = generator::pose::Poser::new(&floating_model, &floating_model.parameters.iter().map(|(_, v)| *v).collect::<Vec<_>>()).unwrap();
    let base = &floating_poser.bodies.iter().find(|b| b.name == "base").unwrap().shapes;
    assert!(floating_poser.scenery.is_empty() && base.len() == 1 && base[0].solid == "cylinder", "{base:?}");
    // URDF is in SI units: angles in radians, a prismatic joint's travel in metres, masses in kg.
    assert_eq!((model.unit("waist"), model.unit("right_wrist"), model.unit("mass_torso")), (Some("rad"), Some("m"), Some("kg")));
    // The shapes reach the page, with the bodies' other data.
    let motion = animate::Motion { formulation: "kane", times: &[0.0], q: &vec![0.0; model.coordinates.len()] };
    let html = animate::page(&model, &params, &motion).unwrap();
    let json = html.split(r#"id="data">"#).nth(1).unwrap().split("</script>").next().unwrap();
    let data: serde_json::Value = serde_json::from_str(json).unwrap();
    let drawn = data["bodies"].as_array().unwrap().iter().find(|b| b["name"] == "torso").unwrap()["shapes"].clone();
    assert_eq!(
        (drawn[0]["solid"].clone(), drawn[0]["sizes"].clone(), drawn[1]["solid"].clone()),
        ("box".into(), serde_json::json!([0.2, 0.3, 0.5]), "sphere".into())
    );
    // The hand's mesh reaches the page as its scaled vertices and its triangles.
    let hand = data["bodies"].as_array().unwrap().iter().find(|b| b["name"] == "right_hand").unwrap()["shapes"][0].clone();
    let points: Vec<f64> = serde_json::from_value(hand["points"].clone()).unwrap();
    let expected = [-0.02, -0.05, -0.01, 0.02, -0.05, -0.01, 0.02, 0.01, 0.01, -0.02, 0.01, 0.01];
    assert!(points.len() == 12 && points.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-9), "{points:?}");
    assert_eq!(hand["triangles"], serde_json::json!([0, 1, 2, 0, 2, 3]));
    assert_eq!((data["scenery"][0]["solid"].clone(), data["scenery"][0]["sizes"].clone()), ("cylinder".into(), serde_json::json!([0.15, 0.1])));
}

/// A RON body drawn as an STL mesh: the file found beside the model (or beside the URDF a model
/// includes, from another folder), scaled and placed; a mesh that is not there or not an STL is
/// refused when drawn, one scaled by zero when read, located at its field, the path in the
/// message.
#[test]
fn a_body_is_drawn_as_a_mesh_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("robot/parts")).unwrap();
    std::fs::copy(fixture("hand.stl"), dir.path().join("robot/parts/hand.stl")).unwrap();
    let model_with = |shape: &str| {
        format!(
            r#"Model(
        name: "held",
        parameters: {{ "m": 1.0, "mm": 0.001 }},
        coordinates: ["x"],
        frames: [Frame(name: "block", parent: "world", translation: ["x", "0", "0"])],
        bodies: [Body(name: "block", frame: "block", mass: "m", inertia: PointMass,
            shape: {shape})],
        forces: [Potential(name: "spring", expr: "x^2/2")],
        quasi_velocities: QuasiVelocities(full: ["x'"], reduced: ["x'"]),
        initial: Initial(q: {{"x": "0.1"}}, qdot: {{"x": "0"}}),
    )"#
        )
    };
    let load = |name: &str, shape: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, model_with(shape)).unwrap();
        generator::model::load(&path)
    };
    let model = load("held.ron", r#"Mesh(file: "robot/parts/hand.stl", scale: ["mm", "-mm", "mm"], origin: ["0", "0", "0.5"])"#).unwrap();
    let poser = generator::pose::Poser::new(&model, &[1.0, 0.001]).unwrap();
    let s = &poser.bodies[0].shapes[0];
    assert_eq!((s.solid, s.sizes.clone(), s.origin), ("mesh", vec![0.001, -0.001, 0.001], [0.0, 0.0, 0.5]));
    assert_eq!(s.mesh.as_ref().unwrap().triangles.len(), 2);
    // Scenery: shapes fixed to the world, a table and the mesh again; a bad size is located.
    let path = dir.path().join("scenery.ron");
    let text = model_with(r#"Sphere(radius: "0.1")"#).replace(
        "        forces:",
        r#"        scenery: Compound([Box(size: ["1", "1", "0.05"], origin: ["0", "0", "-0.1"]), Mesh(file: "robot/parts/hand.stl", scale: ["mm", "mm", "mm"])]),
        forces:"#,
    );
    std::fs::write(&path, &text).unwrap();
    let poser = generator::pose::Poser::new(&generator::model::load(&path).unwrap(), &[1.0, 0.001]).unwrap();
    assert_eq!(poser.scenery.iter().map(|s| s.solid).collect::<Vec<_>>(), ["box", "mesh"]);
    assert_eq!((poser.scenery[0].sizes.clone(), poser.scenery[0].origin), (vec![1.0, 1.0, 0.05], [0.0, 0.0, -0.1]));
    std::fs::write(&path, text.replace(r#"size: ["1", "1", "0.05"]"#, r#"size: ["1", "-m", "0.05"]"#)).unwrap();
    let e = generator::model::load(&path).unwrap_err();
    assert!(e.place == "scenery[0].size[1]" && e.location.is_some() && e.to_string().contains("not a positive number"), "{e}");
    // Included from another folder, the robot's mesh is read from the robot's folder.
    std::fs::copy(fixture("tree.urdf"), dir.path().join("robot/tree.urdf")).unwrap();
    let urdf = std::fs::read_to_string(dir.path().join("robot/tree.urdf")).unwrap().replace("package://tree_description/hand.stl", "parts/hand.stl");
    std::fs::write(dir.path().join("robot/tree.urdf"), urdf).unwrap();
    let path = dir.path().join("with_robot.ron");
    std::fs::write(
        &path,
        r#"Model(name: "with_robot", urdf: Urdf(file: "robot/tree.urdf", base: Fixed), parameters: {}, coordinates: [], frames: [], bodies: [], forces: [])"#,
    )
    .unwrap();
    let model = generator::model::load(&path).unwrap();
    let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
    let poser = generator::pose::Poser::new(&model, &params).unwrap();
    let hand = &poser.bodies.iter().find(|b| b.name == "right_hand").unwrap().shapes[0];
    assert_eq!((hand.solid, hand.mesh.as_ref().map(|m| m.vertices.len())), ("mesh", Some(4)));
    // Refusals, located at the mesh's field. A file that is missing, not a mesh of its format or
    // of a format not read leaves the model
    // to derive and run (a worker elsewhere has no mesh files) but refuses to draw it; a scale
    // of zero or of two factors is refused on reading.
    std::fs::write(dir.path().join("robot/parts/notes.stl"), "these are notes").unwrap();
    std::fs::write(dir.path().join("robot/parts/notes.dae"), "these are notes").unwrap();
    std::fs::write(dir.path().join("robot/parts/hand.glb"), "glTF").unwrap();
    for (shape, field, says, drawn) in [
        (r#"Mesh(file: "robot/parts/gone.stl")"#, "\"robot/parts/gone.stl\"", "cannot be read", true),
        (r#"Mesh(file: "robot/parts/notes.stl")"#, "\"robot/parts/notes.stl\"", "not an STL file", true),
        (r#"Mesh(file: "robot/parts/notes.dae")"#, "\"robot/parts/notes.dae\"", "not a COLLADA file", true),
        (r#"Mesh(file: "robot/parts/hand.glb")"#, "\"robot/parts/hand.glb\"", "`.stl`, `.dae` or `.obj`", true),
        (r#"Mesh(file: "robot/parts/hand.stl", scale: ["1", "0", "1"])"#, "\"0\"", "other than zero", false),
        (r#"Mesh(file: "robot/parts/hand.stl", scale: ["1", "1"])"#, "\"1\"", "three factors", false),
    ] {
        let e = match load("bad.ron", shape) {
            Ok(model) if drawn => {
                let motion = animate::Motion { formulation: "kane", times: &[0.0], q: &[0.0] };
                match animate::page(&model, &[1.0, 0.001], &motion) {
                    Err(animate::AnimateError::Mesh(e)) => *e,
                    other => panic!("{shape}: drawn as {:?}", other.map(|_| "a page")),
                }
            }
            Ok(_) => panic!("{shape}: read"),
            Err(e) => {
                assert!(!drawn, "{shape}: {e}");
                e
            }
        };
        let text = model_with(shape);
        let (line, col) = e.location.expect("located");
        let at: usize = text.split_inclusive('\n').take(line - 1).map(str::len).sum::<usize>() + col - 1;
        assert!(text[at..].starts_with(field), "{shape}: {e} at {line}:{col}");
        assert!(e.to_string().contains(says) && e.to_string().contains("bad.ron"), "{shape}: {e}");
    }
    // The tool refuses such a page before the run: exit 1, the place shown, nothing written; the
    // same model runs without a page.
    load("bad.ron", r#"Mesh(file: "robot/parts/gone.stl")"#).unwrap();
    let args = ["simulate", "bad.ron", "--t-end", "0.1", "--dt-out", "0.05"];
    let out = multibody(dir.path(), &[&args[..], &["--animate", "bad.html"]].concat());
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.code() == Some(1) && said.contains("bad.ron:7:31") && said.contains("cannot be read"), "{said}");
    assert!(!dir.path().join("bad.html").exists() && !dir.path().join("held_kane.csv").exists() && !dir.path().join("held_reduced_volterra.csv").exists());
    ok(&multibody(dir.path(), &args));
    assert!(dir.path().join("held_reduced_volterra.csv").exists());
}

/// Every refusal names the file, the line and column of the element at fault, and the fix.
#[test]
fn refusals_are_located_in_the_xml() {
    let tree = std::fs::read_to_string(fixture("tree.urdf")).unwrap();
    let cases: [(&str, &str, &str); 10] = [
        (r#"<joint name="waist" type="continuous">"#, r#"<joint name="waist" type="floating">"#, "joint `waist` is floating"),
        (r#"<joint name="waist" type="continuous">"#, r#"<joint name="waist" type="screw">"#, "joint `waist` has type `screw`"),
        (r#"<child link="left_lower"/>"#, r#"<child link="right_hand"/>"#, "closes a loop"),
        (r#"<parent link="base"/><child link="torso"/>"#, r#"<parent link="base"/><child link="nowhere"/>"#, "`nowhere` is not a link"),
        (r#"<mass value="0.4"/>"#, r#"<mass value="-0.4"/>"#, "has mass -0.4"),
        (r#"ixx="0.0008" iyy="0.0004" izz="0.0008""#, r#"ixx="0.0008" iyy="0.0004" izz="0.008""#, "no rigid body's"),
        (r#"<axis xyz="0 -1 0"/>"#, r#"<axis xyz="0 0 0"/>"#, "zero axis"),
        (r#"<robot name="tree">"#, r#"<robot name="tree"><link name="stray"/>"#, "2 roots"),
        (r#"<sphere radius="0.08"/>"#, r#"<sphere radius="-0.08"/>"#, "visual sphere has radius -0.08"),
        (r#"<box size="0.2 0.3 0.5"/>"#, r#"<box size="0.2 0 0.5"/>"#, "visual box has a side 0"),
    ];
    for (from, to, words) in cases {
        assert!(tree.contains(from), "{from}");
        let xml = tree.replacen(from, to, 1);
        let e = model_file("tree.urdf", &xml, &UrdfOptions::default()).expect_err(words);
        let text = e.render(false);
        assert!(text.contains(words) && text.contains("tree.urdf:") && text.contains("help:"), "{words}: {text}");
        let (line, _) = e.location.unwrap_or_else(|| panic!("{words}: located"));
        let at = xml.lines().nth(line - 1).unwrap();
        assert!(!at.trim().is_empty(), "{words}: line {line}");
    }
    // Malformed XML: the parser's place.
    let e = model_file("tree.urdf", &tree.replacen("</link>", "</lnk>", 1), &UrdfOptions::default()).unwrap_err();
    assert!(e.to_string().contains("malformed URDF") && e.location.is_some(), "{e}");
    // A massless link moved by a joint; a floating root with no inertia.
    let massless = tree.replacen(r#"<mass value="0.4"/>"#, r#"<mass value="0"/>"#, 1);
    let e = model_file("tree.urdf", &massless, &UrdfOptions::default()).unwrap_err();
    assert!(e.to_string().contains("joint `right_wrist` moves link `right_hand`") && e.to_string().contains("carry no mass"), "{e}");
    let rootless = tree.replacen(r#"<mass value="4.0"/>"#, r#"<mass value="0"/>"#, 1);
    let e = model_file("tree.urdf", &rootless, &floating([0.0; 3])).unwrap_err();
    assert!(e.to_string().contains("the root link `base` carries no inertia"), "{e}");
}

/// What exporters write that is not a mistake is read: a joint named as the link it moves (its
/// coordinate takes the name with `_`), a quarter turn written to 11 digits, two links whose
/// names read as one identifier, a point mass's inertia written as float noise (iCub's
/// head: all zero but `ixz = 2.4e-35`); a robot with nothing to move on a fixed base (a drone's
/// one link) is refused, located at `<robot>`, and runs on a floating base.
#[test]
fn what_exporters_write_is_read() {
    let tree = std::fs::read_to_string(fixture("tree.urdf")).unwrap();
    let named = tree.replace(r#"<joint name="right_wrist""#, r#"<joint name="right_hand""#);
    assert_ne!(named, tree);
    let text = to_ron(&model_file("tree.urdf", &named, &UrdfOptions::default()).unwrap());
    let model = from_source("tree.urdf", &text).unwrap();
    let names: Vec<String> = model.coordinates.iter().map(|c| c.name()).collect();
    assert!(names.contains(&"right_hand_".to_string()) && model.frames.iter().any(|f| f.name == "right_hand"), "{names:?}");
    // A quarter turn written to 11 digits (anymal's 1.57079632679, whose cosine 4.9e-12 made
    // every rotation dense and a floating anymal take minutes) is the quarter turn written
    // exactly; a turn 3.7e-6 away (1.5708) is the angle given.
    let turned = |rpy: &str| {
        to_ron(
            &model_file("tree.urdf", &tree.replace(r#"xyz="0 -0.3 0" rpy="0 0 0.5""#, &format!(r#"xyz="0 -0.3 0" rpy="{rpy}""#)), &UrdfOptions::default())
                .unwrap(),
        )
    };
    let short = turned("1.57079632679 0 -3.14159265359");
    assert_eq!(short, turned(&format!("{} 0 {}", std::f64::consts::FRAC_PI_2, -std::f64::consts::PI)));
    assert_ne!(short, turned("1.5708 0 -3.14159265359"));
    assert!(!short.contains("e-12") && !short.contains("0.99999"), "{short}");
    // Two links whose names read as one identifier: the second's frame takes `_`.
    let twins = tree.replace(r#""left_lower""#, r#""left-upper""#);
    assert_ne!(twins, tree);
    let model = from_source("tree.urdf", &to_ron(&model_file("tree.urdf", &twins, &UrdfOptions::default()).unwrap())).unwrap();
    let frames: Vec<&str> = model.frames.iter().map(|f| f.name.as_str()).collect();
    assert!(frames.contains(&"left_upper") && frames.contains(&"left_upper_"), "{frames:?}");
    let noise =
        tree.replace(r#"ixx="0.0008" iyy="0.0004" izz="0.0008" ixy="0" ixz="0" iyz="0""#, r#"ixx="0" iyy="0" izz="0" ixy="0" ixz="2.40741e-35" iyz="0""#);
    assert_ne!(noise, tree);
    model_file("tree.urdf", &noise, &UrdfOptions::default()).unwrap();
    // A tensor wrong by more than noise is still refused (the ankle's 1e-20 would pass; 1e-6
    // on a 0.4 kg link is a million times the tolerance).
    let wrong = tree.replace(r#"ixx="0.0008" iyy="0.0004" izz="0.0008""#, r#"ixx="0.0008" iyy="0.0004" izz="0.001201""#);
    assert!(model_file("tree.urdf", &wrong, &UrdfOptions::default()).unwrap_err().to_string().contains("no rigid body's"));
    let dir = tempfile::tempdir().unwrap();
    let drone = dir.path().join("drone.urdf");
    std::fs::write(
        &drone,
        "<?xml version=\"1.0\"?>\n<robot name=\"drone\">\n  <link name=\"body\"><inertial><mass value=\"1.5\"/>\n    <inertia ixx=\"0.02\" iyy=\"0.02\" izz=\"0.04\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n</robot>\n",
    )
    .unwrap();
    let Err(e) = generator::model::source_with(&drone, &UrdfOptions::default()) else { panic!("a robot with nothing to move is read") };
    let said = e.render(false);
    assert!(e.location.map(|(line, _)| line) == Some(2) && said.contains("nothing in it moves") && said.contains("--base floating"), "{said}");
    let flying = generator::model::source_with(&drone, &floating([0.0, 0.0, -9.81])).unwrap().model().unwrap();
    assert_eq!(flying.m(), 7);
}

/// A mimic joint follows its master (`q = 2 q_master + 0.1`): no coordinate of its own.
#[test]
fn a_mimic_joint_follows_its_master() {
    let tree = std::fs::read_to_string(fixture("tree.urdf")).unwrap();
    let xml = tree.replacen(
        r#"<limit lower="-1.5" upper="1.5" effort="20" velocity="3"/>"#,
        r#"<limit lower="-1.5" upper="1.5" effort="20" velocity="3"/><mimic joint="left_shoulder" multiplier="2" offset="0.1"/>"#,
        1,
    );
    let def = model_file("tree.urdf", &xml, &UrdfOptions::default()).unwrap();
    assert!(!def.coordinates.contains(&"left_elbow".to_string()));
    let elbow = def.frames.iter().find(|f| f.name == "left_lower").unwrap();
    let text = to_ron(&def);
    assert!(text.contains("2.0*left_shoulder + 0.1"), "{elbow:?}");
    let model = from_source("tree.urdf", &text).unwrap();
    let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    check_formulations_agree("mimic", &d, &model, 3, 9);
}

/// The command line reads a URDF as any model, from a folder with no Rust toolchain: a fixed
/// and a floating base, gravity off, limits as events that stop the run.
#[test]
fn the_command_line_runs_a_urdf() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixture("tree.urdf"), dir.path().join("tree.urdf")).unwrap();
    let text = ok(&multibody(dir.path(), &["compare", "tree.urdf", "--t-end", "0.2", "--repeats", "1"]));
    assert!(text.contains("| kane | 11 | 5 |"), "{text}");
    let text = ok(&multibody(dir.path(), &["compare", "tree.urdf", "--base", "floating", "--gravity", "0,0,0", "--t-end", "0.1", "--repeats", "1"]));
    assert!(text.contains("momentum err (base_z)") && text.contains("| reduced_volterra | 21 | 8 |"), "{text}");
    // At rest without gravity the energy is zero: its relative error is undefined, shown `-`.
    assert!(!text.contains("NaN") && text.lines().any(|l| l.starts_with("| kane | 24 | 11 |") && l.split(" | ").nth(5) == Some("-")), "{text}");
    let text = ok(&multibody(dir.path(), &["inspect", "tree.urdf"]));
    assert!(text.contains("joint limits (not enforced): left_shoulder in [-2.0, 2.0]"), "{text}");
    // Gravity pulls the left arm's shoulder past its limit at -2: the run stops there.
    let text = ok(&multibody(dir.path(), &["simulate", "tree.urdf", "--limits", "stop", "--q", "left_shoulder=-1.9", "--t-end", "3"]));
    assert!(text.contains("left_shoulder_lower (stop)") || text.contains("(stopped there by event"), "{text}");
}

/// The space manipulator of `docs/robots/` (the model `docs/robots.md` and its example run): a
/// satellite with a 7-joint arm, from a RON file that includes its URDF and adds torque inputs.
/// Driven by a PD law, every formulation follows the same motion, the energy balance (the
/// motors' work taken out) holds, and the satellite's linear momentum, conserved as the arm
/// moves, is kept by the reduced method to round-off while the others keep it only to their
/// tolerance; the angular momentum (Noether's charge of a world rotation) is conserved.
#[test]
fn the_space_manipulator_keeps_its_momentum_under_control() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/robots/space_manipulator.ron");
    let source = generator::model::load(path).unwrap();
    let seam = load::evaluate(&source, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
    let ignorable: Vec<String> = seam.ignorable.iter().map(|&j| source.coordinates[j].name()).collect();
    assert_eq!(ignorable, ["base_x", "base_y", "base_z"]);
    let joints: Vec<usize> = (1..=7).map(|k| seam.coordinate_index(&format!("joint{k}")).unwrap()).collect();
    let law = move |t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| {
        for (k, (&j, u)) in joints.iter().zip(u.iter_mut()).enumerate() {
            *u = 40.0 * (0.6 * (0.8 * t + k as f64).sin() - q[j]) + 8.0 * (0.48 * (0.8 * t + k as f64).cos() - qd[j]);
        }
    };
    let (q0, qd0) = seam.initial.clone().unwrap();
    let times: Vec<f64> = (0..=20).map(|i| 0.1 * i as f64).collect();
    let worst = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut ends = Vec::new();
    for (kind, settings) in
        FormulationKind::ALL.into_iter().flat_map(|k| [(k, Settings::paper(2.0)), (k, Settings { rtol: 1e-11, atol: 1e-11, ..Settings::tight(2.0) })])
    {
        let (sys, y0) = System::start(&seam, kind, seam.default_params.clone(), &q0, &qd0).unwrap();
        let sys = sys.with_controller(runtime::inputs::Controller::new(law.clone()));
        let run = runtime::trajectory::simulate(&sys, &y0, &times, &settings, &mut |_| {}).unwrap();
        let inv = &run.invariants;
        let scale = inv.momentum0.iter().fold(0.0f64, |m, p| m.max(p.abs()));
        assert!(scale > 1.0, "the satellite moves: momenta {:?}", inv.momentum0);
        let drift = inv.momentum_error.iter().map(|d| worst(d)).fold(0.0, f64::max);
        if kind == FormulationKind::ReducedVolterra {
            assert!(drift < 1e-13 * scale, "{kind} at rtol {}: momentum drifts {drift:e}", settings.rtol);
        } else if settings.rtol > 1e-6 {
            // At the paper's tolerance the others' momenta drift by many orders more than
            // round-off: the reduced method's exactness is not a property of the motion.
            assert!(drift > 1e-9 * scale, "{kind}: momentum drifts only {drift:e}");
        }
        if settings.rtol < 1e-6 {
            assert!(drift < 1e-9 * scale, "{kind}: momentum drifts {drift:e}");
            // The angular momentum is conserved too (the motors' torques are internal), though
            // no coordinate is ignorable for it: every formulation keeps it to its tolerance.
            for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                let l = |i: usize| {
                    let (q, qd) = (&inv.coordinates[i], &inv.rates[i]);
                    let xi = generator::model::world_rotation(&seam.coordinates, q, axis).unwrap();
                    runtime::monitor::momentum_along(&seam, 0.0, &seam.default_params, q, qd, &xi).unwrap()
                };
                let l0 = l(0);
                assert!(l0.abs() > 1e-3 || axis[0] == 1.0, "the arm turns about {axis:?}: {l0}");
                for i in 1..times.len() {
                    assert!((l(i) - l0).abs() < 1e-9 * (1.0 + l0.abs()), "{kind}: angular momentum about {axis:?} drifts from {l0} to {}", l(i));
                }
            }
            assert!(worst(&inv.energy_error) < 1e-9, "{kind}: the energy balance is off by {:e}", worst(&inv.energy_error));
            ends.push(inv.coordinates.last().unwrap().clone());
        }
    }
    for end in &ends[1..] {
        for (a, b) in end.iter().zip(&ends[0]) {
            assert!((a - b).abs() < 1e-8, "{end:?} against {:?}", ends[0]);
        }
    }
}

/// A star: a hub with three branches of two tilted joints each, every body moved by at most a
/// third of the rates. Derived for Kane's and the reduced forms alone, its mechanics keep `M`
/// and `N` as built (`mechanics::derive_for`): the right-hand sides are the same as with every
/// formulation derived (and `M`, `N` simplified), at random states, to round-off.
#[test]
fn a_short_branched_tree_derived_for_kane_alone_runs_the_same() {
    let mut xml = String::from(
        r#"<robot name="star"><link name="hub"><inertial><mass value="5"/><inertia ixx="0.3" iyy="0.4" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial></link>"#,
    );
    for k in 0..3 {
        let turn = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
        xml += &format!(
            r#"<link name="a{k}"><inertial><origin xyz="0.1 0 0"/><mass value="1.{k}"/><inertia ixx="0.01" iyy="0.02" izz="0.025" ixy="0.001" ixz="0" iyz="0"/></inertial></link>
               <link name="b{k}"><inertial><origin xyz="0.08 0.01 0"/><mass value="0.{k}7"/><inertia ixx="0.004" iyy="0.006" izz="0.007" ixy="0" ixz="0.0005" iyz="0"/></inertial></link>
               <joint name="hip{k}" type="revolute"><parent link="hub"/><child link="a{k}"/><origin xyz="0.2 0 0" rpy="0 0.{k} {turn}"/><axis xyz="0 0.6 0.8"/></joint>
               <joint name="knee{k}" type="continuous"><parent link="a{k}"/><child link="b{k}"/><origin xyz="0.2 0 0"/><axis xyz="0 1 0"/></joint>"#
        );
    }
    xml += "</robot>";
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("star.urdf");
    std::fs::write(&path, &xml).unwrap();
    let model = generator::model::source_with(&path, &UrdfOptions::default()).unwrap().model().unwrap();
    assert_eq!(model.m(), 6);
    // The path is taken: `M` as built is not the simplified one.
    let (built, settled) = (generator::formulation::mechanics::derive_for(&model, false), generator::formulation::mechanics::derive(&model));
    let size = |m: &generator::symbolic::Matrix| (0..6).flat_map(|i| (0..6).map(move |j| (i, j))).map(|(i, j)| m.get(i, j).tree_size() as u64).sum::<u64>();
    assert_ne!(size(&built.mass), size(&settled.mass), "M kept as built on the star");
    let all = load::evaluate(&model, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
    let mut rng = generator::symbolic::SplitMix(7);
    for kind in [FormulationKind::Kane, FormulationKind::ReducedVolterra] {
        let alone = load::evaluate_only(&model, Some(kind), load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap().model;
        assert_eq!(alone.kinds(), [kind]);
        for _ in 0..5 {
            let q: Vec<f64> = (0..6).map(|_| rng.uniform(-1.5, 1.5)).collect();
            let qd: Vec<f64> = (0..6).map(|_| rng.uniform(-2.0, 2.0)).collect();
            let (a, ya) = System::start(&all, kind, all.default_params.clone(), &q, &qd).unwrap();
            let (b, yb) = System::start(&alone, kind, alone.default_params.clone(), &q, &qd).unwrap();
            assert_eq!(ya.len(), yb.len());
            let (mut da, mut db) = (vec![0.0; ya.len()], vec![0.0; yb.len()]);
            a.rhs(0.0, &ya, &mut da).unwrap();
            b.rhs(0.0, &yb, &mut db).unwrap();
            let scale = da.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for (x, y) in da.iter().zip(&db) {
                assert!((x - y).abs() < 1e-12 * scale, "{kind}: {x} against {y}");
            }
        }
    }
}
