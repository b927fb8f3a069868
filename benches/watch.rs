//! `multibody watch` from a save to the new run served (the issue "See it", item 4: under one
//! second for the paper's scenes): each scene's file copied to a temporary folder and watched;
//! saved `SAVES` times, each with a comment line of its own (new bytes, the same model); the time from each save until the server's news
//! carries the next run (the page, which asks four times a second, shows it within a further
//! quarter second). Writes `docs/benchmarks/watch.json`; `docs/tool.md` quotes it.
//!
//! ```sh
//! cargo bench --bench watch
//! ```

use std::io::BufRead;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SCENES: [&str; 3] = ["cart_pendulum", "three_body", "satellite_boom"];
const SAVES: usize = 7;

#[path = "../tests/it/common/http.rs"]
mod http;

fn run_number(port: u16, token: &str) -> u64 {
    let news: serde_json::Value = serde_json::from_str(&http::get(port, &format!("/status?token={token}")).1).unwrap();
    assert!(news["error"].is_null(), "{news}");
    news["run"].as_u64().unwrap()
}

fn main() {
    let exe = env!("CARGO_BIN_EXE_multibody");
    let mut records = Vec::new();
    for scene in SCENES {
        let dir = tempfile::tempdir().unwrap();
        let text = std::fs::read_to_string(format!("{}/models/{scene}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let file = dir.path().join(format!("{scene}.ron"));
        std::fs::write(&file, &text).unwrap();
        let mut child =
            Command::new(exe).args(["watch", &format!("{scene}.ron")]).current_dir(dir.path()).stdout(Stdio::piped()).stderr(Stdio::null()).spawn().unwrap();
        let (lines, first) = std::sync::mpsc::channel();
        let stdout = child.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stdout).lines() {
                let _ = lines.send(line.unwrap_or_default());
            }
        });
        let first: String = first.recv_timeout(Duration::from_secs(60)).unwrap();
        let address = first.split_whitespace().find(|w| w.starts_with("http://127.0.0.1:")).unwrap().to_string();
        let (host, token) = address.split_once("/?token=").unwrap();
        let port: u16 = host.rsplit(':').next().unwrap().parse().unwrap();
        while run_number(port, token) < 1 {
            std::thread::sleep(Duration::from_millis(10));
        }
        // Each save changes the file (a comment line), so that every save is a new run.
        let mut seconds = Vec::new();
        for k in 0..SAVES {
            let before = run_number(port, token);
            let saved = Instant::now();
            std::fs::write(&file, format!("{text}\n// save {k}\n")).unwrap();
            while run_number(port, token) == before {
                assert!(saved.elapsed() < Duration::from_secs(60), "{scene}: no new run");
                std::thread::sleep(Duration::from_millis(5));
            }
            seconds.push(saved.elapsed().as_secs_f64());
        }
        let _ = child.kill();
        let _ = child.wait();
        seconds.sort_by(f64::total_cmp);
        eprintln!("{scene}: save to run {:.3} s (median of {SAVES}), {:.3} s at most", seconds[SAVES / 2], seconds[SAVES - 1]);
        records.push(serde_json::json!({ "scene": scene, "median_s": seconds[SAVES / 2], "max_s": seconds[SAVES - 1], "saves": SAVES }));
    }
    let json = serde_json::json!({
        "command": "cargo bench --bench watch",
        "about": "multibody watch on the paper's scenes: from a save of the model file to the server's news of the new run (derived, run, written), the median and the largest of the saves; the page asks every 0.25 s and reloads",
        "cores": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "records": records,
    });
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/benchmarks/watch.json");
    std::fs::write(&out, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    eprintln!("wrote {}", out.display());
}
