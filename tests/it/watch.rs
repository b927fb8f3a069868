//! `multibody watch`: the live loop, run as a user runs it on a model file of their own. A test
//! edits the file and waits for the new run; a broken edit shows its located error and keeps
//! the loop going; the server answers nothing without its token.

use crate::common::http::get;
use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The watch process, killed when the test ends however it ends.
struct Watching(Child);

impl Drop for Watching {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `multibody watch ARGS` started in `dir`: the process (killed when dropped), and the port and
/// token of the address it prints.
fn watch(dir: &Path, args: &[&str]) -> (Watching, u16, String) {
    let mut child =
        Command::new(env!("CARGO_BIN_EXE_multibody")).arg("watch").args(args).current_dir(dir).stdout(Stdio::piped()).stderr(Stdio::null()).spawn().unwrap();
    let stdout = child.stdout.take().unwrap();
    let watching = Watching(child);
    // Its output read to the end (a closed pipe would end the tool, as it ends `... | head`).
    let (lines, first) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stdout).lines() {
            let _ = lines.send(line.unwrap_or_default());
        }
    });
    let first = first.recv_timeout(Duration::from_secs(60)).expect("the watch prints its address");
    // `watching MODEL: the motion at http://127.0.0.1:PORT/?token=TOKEN ...`
    let address = first.split_whitespace().find(|w| w.starts_with("http://127.0.0.1:")).unwrap_or_else(|| panic!("no address in `{first}`"));
    let (host, token) = address.split_once("/?token=").unwrap();
    let port: u16 = host.rsplit(':').next().unwrap().parse().unwrap();
    (watching, port, token.to_string())
}

/// The news the page polls for, once it satisfies `until` (within two minutes).
fn wait_for(port: u16, token: &str, until: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
    let start = Instant::now();
    loop {
        let (status, body) = get(port, &format!("/status?token={token}"));
        assert_eq!(status, 200, "{body}");
        let news: serde_json::Value = serde_json::from_str(&body).unwrap();
        if until(&news) {
            return news;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "the watch did not get there: {news}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn params_written(dir: &Path) -> serde_json::Value {
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("cart_pendulum_reduced_volterra.json")).unwrap()).unwrap();
    json["params"].clone()
}

#[test]
fn watch_runs_again_on_every_save_and_shows_a_broken_model_s_error_without_stopping() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("cart_pendulum.ron");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/models/cart_pendulum.ron")).unwrap();
    assert!(text.contains(r#""M": 2.0,"#));
    std::fs::write(&model, &text).unwrap();
    let (_watching, port, token) = watch(dir.path(), &["cart_pendulum.ron", "--t-end", "2"]);
    let token = token.as_str();
    assert_eq!(token.len(), 32, "128 random bits in hex: {token}");

    let news = wait_for(port, token, |n| n["run"] == 1);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(params_written(dir.path())["M"], 2.0);
    // The page is the animation, made live with this run's number and the token.
    let (status, page) = get(port, &format!("/?token={token}"));
    assert_eq!(status, 200);
    assert!(page.contains(&format!(r#"const live = {{"run":1,"token":"{token}"}};"#)), "the page is not live");
    assert!(page.contains(r#""model":"cart_pendulum""#));
    // Nothing without the token, nor with another.
    assert_eq!(get(port, "/status").0, 403);
    assert_eq!(get(port, "/?token=0123").0, 403);
    assert_eq!(get(port, &format!("/status?token={}", "0".repeat(32))).0, 403);

    // A save: the next run has the new mass, in the page's run number and in the files.
    std::fs::write(&model, text.replace(r#""M": 2.0,"#, r#""M": 3.0,"#)).unwrap();
    let news = wait_for(port, token, |n| n["run"] == 2);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(params_written(dir.path())["M"], 3.0);
    let (_, page) = get(port, &format!("/?token={token}"));
    assert!(page.contains(r#"const live = {"run":2,"#));

    // A broken save: its located error, the last good run kept, the loop still going.
    std::fs::write(&model, text.replace(r#""M": 2.0,"#, r#""M": 4.0 +,"#)).unwrap();
    let news = wait_for(port, token, |n| !n["error"].is_null());
    let error = news["error"].as_str().unwrap();
    assert!(error.contains("cart_pendulum.ron:7:"), "the error is not located: {error}");
    assert_eq!(news["run"], 2);
    assert_eq!(params_written(dir.path())["M"], 3.0);

    // Fixed: a new run, and the error gone.
    std::fs::write(&model, text.replace(r#""M": 2.0,"#, r#""M": 5.0,"#)).unwrap();
    let news = wait_for(port, token, |n| n["run"] == 3);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(params_written(dir.path())["M"], 5.0);

    // Gone (an editor's save that removes the file first): told, then run again once back.
    std::fs::remove_file(&model).unwrap();
    let news = wait_for(port, token, |n| !n["error"].is_null());
    assert!(news["error"].as_str().unwrap().contains("cannot read"), "{news}");
    assert_eq!(news["run"], 3);
    std::fs::write(&model, text.replace(r#""M": 2.0,"#, r#""M": 5.0,"#)).unwrap();
    let news = wait_for(port, token, |n| n["run"] == 4);
    assert!(news["error"].is_null(), "{news}");
}

/// A RON model that includes a URDF: a save of the URDF runs the model again too.
#[test]
fn watch_follows_the_urdf_a_model_includes() {
    let dir = tempfile::tempdir().unwrap();
    let docs = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/robots/");
    std::fs::copy(format!("{docs}space_manipulator.ron"), dir.path().join("arm.ron")).unwrap();
    let urdf = std::fs::read_to_string(format!("{docs}space_manipulator.urdf")).unwrap();
    assert!(urdf.contains(r#"<mass value="8.0"/>"#));
    std::fs::write(dir.path().join("space_manipulator.urdf"), &urdf).unwrap();
    let (_watching, port, token) = watch(dir.path(), &["arm.ron", "--t-end", "0.2"]);
    let token = token.as_str();
    let written = || -> serde_json::Value {
        let json: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("space_manipulator_reduced_volterra.json")).unwrap()).unwrap();
        json["params"]["mass_link1"].clone()
    };
    let news = wait_for(port, token, |n| n["run"] == 1);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(written(), 8.0);
    // The URDF saved, the RON untouched: a new run with the new mass.
    std::fs::write(dir.path().join("space_manipulator.urdf"), urdf.replacen(r#"<mass value="8.0"/>"#, r#"<mass value="9.5"/>"#, 1)).unwrap();
    let news = wait_for(port, token, |n| n["run"] == 2);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(written(), 9.5);
}

#[test]
fn watch_needs_a_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = crate::common::multibody(dir.path(), &["watch", "cart_pendulum"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`watch` follows a model file, and `cart_pendulum` is none"), "{err}");
}

/// A model drawn with an STL mesh: saving the mesh (the model untouched) runs again, and the
/// page shows the new mesh (the tool reads a mesh once while its file stays the same).
#[test]
fn watch_follows_the_mesh_a_model_draws() {
    let dir = tempfile::tempdir().unwrap();
    let tetra = |size: f64| {
        let corners = [[0.0, 0.0, 0.0], [size, 0.0, 0.0], [0.0, size, 0.0], [0.0, 0.0, size]];
        let mut stl = String::from("solid t\n");
        for f in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            stl += "facet normal 0 0 0\nouter loop\n";
            for k in f {
                let [x, y, z] = corners[k];
                stl += &format!("vertex {x} {y} {z}\n");
            }
            stl += "endloop\nendfacet\n";
        }
        stl + "endsolid t\n"
    };
    std::fs::write(dir.path().join("part.stl"), tetra(0.25)).unwrap();
    std::fs::write(
        dir.path().join("swing.ron"),
        r#"Model(name: "swing", parameters: { "g": 9.81 }, coordinates: ["th"],
    frames: [Frame(name: "arm", parent: "world", rotation: [Z("th")]), Frame(name: "tip", parent: "arm", translation: ["1", "0", "0"])],
    bodies: [Body(name: "tip", frame: "tip", mass: "1", inertia: PointMass, shape: Mesh(file: "part.stl"))],
    forces: [Gravity(vector: ["0", "-g", "0"])],
    quasi_velocities: QuasiVelocities(full: ["th'"], reduced: ["th'"]),
    initial: Initial(q: {"th": "-0.5"}, qdot: {"th": "0"}))"#,
    )
    .unwrap();
    let (_watching, port, token) = watch(dir.path(), &["swing.ron", "--t-end", "0.2", "--dt-out", "0.05"]);
    let token = token.as_str();
    // The largest coordinate of the mesh the served page draws.
    let reach = || -> f64 {
        let (status, page) = get(port, &format!("/?token={token}"));
        assert_eq!(status, 200);
        let data: serde_json::Value = serde_json::from_str(page.split(r#"id="data">"#).nth(1).unwrap().split("</script>").next().unwrap()).unwrap();
        data["bodies"][0]["shapes"][0]["points"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).fold(0.0, f64::max)
    };
    let news = wait_for(port, token, |n| n["run"] == 1);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(reach(), 0.25);
    std::fs::write(dir.path().join("part.stl"), tetra(0.5)).unwrap();
    let news = wait_for(port, token, |n| n["run"] == 2);
    assert!(news["error"].is_null(), "{news}");
    assert_eq!(reach(), 0.5);
}
