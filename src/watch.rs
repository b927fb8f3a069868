//! `watch`: the live modelling loop. The model file, and every file a run read (a URDF it
//! includes, an input's series, a mesh), are read ten times a second; when their bytes change
//! (a file over 1 MB, such as a robot's mesh, by its size and modification time) and then hold
//! still for 60 ms (an editor's save can take several writes), the model is derived and run
//! again exactly as `simulate` runs it, writing the same
//! files, and the page of the motion, served on 127.0.0.1 behind a random token, reloads with
//! its camera and time kept. A model's error is told in the terminal, located, and over the
//! page; the loop goes on, the last good run still shown.

use crate::simulate::{SimulateArgs, run};
use crate::{CliError, print};
use clap::Args;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(Args, Debug, Clone, PartialEq)]
pub struct WatchArgs {
    #[command(flatten)]
    pub simulate: SimulateArgs,
    /// The port the page is served on, on 127.0.0.1 only (default: one the system picks).
    #[arg(long, default_value_t = 0)]
    pub port: u16,
}

/// What the server shows: the run's number, its page (made live), and the last error.
#[derive(Default)]
struct Shown {
    run: u64,
    page: Option<String>,
    error: Option<String>,
}

/// How often the model file is read, and how long its bytes must hold still before a run.
const POLL: Duration = Duration::from_millis(100);
const SETTLE: Duration = Duration::from_millis(60);

/// A watched file larger than this is followed by its size and modification time, not its
/// bytes: a robot's meshes, tens of megabytes, read twice a poll would keep a core busy.
const READ_UP_TO: u64 = 1 << 20;

/// What a poll sees of a watched file: its bytes or, larger than [`READ_UP_TO`], its size and
/// modification time.
#[derive(Debug, PartialEq)]
enum Seen {
    Bytes(Vec<u8>),
    Stamp(u64, Option<std::time::SystemTime>),
}

/// What a poll sees of `path` (its bytes read bounded, as the loader reads a model or an
/// input's series, whatever the path is).
fn seen(path: &Path) -> Result<Seen, files::FileError> {
    match std::fs::metadata(path) {
        Ok(m) if m.len() > READ_UP_TO => Ok(Seen::Stamp(m.len(), m.modified().ok())),
        _ => files::read_bounded(path, 64 << 20).map(Seen::Bytes),
    }
}

pub fn watch(args: &WatchArgs) -> Result<(), CliError> {
    let model = &args.simulate.model;
    if !model.is_file() {
        return Err(CliError::WatchNeedsFile { given: files::printable_path(model) });
    }
    let mut simulate = args.simulate.clone();
    let stem = model.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let page_path = simulate.animate.clone().unwrap_or_else(|| simulate.out.join(format!("{stem}.html")));
    simulate.animate = Some(page_path.clone());
    files::check_output(&page_path)?;
    let token = token()?;
    let server = tiny_http::Server::http(("127.0.0.1", args.port)).map_err(|e| CliError::Serve { port: args.port, reason: e.to_string() })?;
    let port = server.server_addr().to_ip().map_or(args.port, |a| a.port());
    let shown = Arc::new(Mutex::new(Shown::default()));
    {
        let (shown, token) = (shown.clone(), token.clone());
        std::thread::spawn(move || {
            for request in server.incoming_requests() {
                answer(request, &shown, &token);
            }
        });
    }
    print(&format!(
        "watching {}: the motion at http://127.0.0.1:{port}/?token={token} (written to {} too); Ctrl-C stops\n",
        files::printable_path(model),
        files::printable_path(&page_path)
    ))?;
    // The files watched: the model's, then every other file a run read (a URDF it includes,
    // an input's series, a mesh). What the last run saw of them; `None` after a failed read (run
    // again when they are back, even unchanged: an editor's save may remove a file a moment).
    let mut watched = vec![model.clone()];
    let mut last: Option<Vec<Seen>> = None;
    let mut told_unreadable = false;
    loop {
        match settled(&watched) {
            Ok(bytes) if last.as_ref() == Some(&bytes) => {}
            Ok(bytes) => {
                last = Some(bytes);
                told_unreadable = false;
                let started = Instant::now();
                let outcome = run(&simulate).and_then(|w| Ok((read_page(&page_path)?, w.map(|e| CliError::Run(e).to_string()))));
                let mut s = shown.lock().unwrap_or_else(|p| p.into_inner());
                let before = watched.len();
                for path in files::inputs() {
                    if !watched.contains(&path) {
                        watched.push(path);
                    }
                }
                if let Some(bytes) = last.as_mut() {
                    bytes.extend(watched[before..].iter().map(|p| seen(p).unwrap_or(Seen::Bytes(Vec::new()))));
                }
                match outcome {
                    Ok((page, stopped)) => {
                        s.run += 1;
                        s.page = Some(page);
                        s.error = stopped;
                        eprintln!("run {} ready in {:.2} s; watching for the next change", s.run, started.elapsed().as_secs_f64());
                    }
                    Err(e) => {
                        eprintln!("{}", crate::describe(&e, std::io::IsTerminal::is_terminal(&std::io::stderr())));
                        eprintln!("(the page keeps the last good run; watching for the next change)");
                        s.error = Some(crate::describe(&e, false));
                    }
                }
            }
            Err(e) => {
                last = None;
                if !told_unreadable {
                    let e = CliError::File(e);
                    eprintln!("error: {e} (watching for it to change)");
                    shown.lock().unwrap_or_else(|p| p.into_inner()).error = Some(e.to_string());
                    told_unreadable = true;
                }
            }
        }
        std::thread::sleep(POLL);
    }
}

/// What a poll sees of the files `paths` once it has held still for [`SETTLE`].
fn settled(paths: &[std::path::PathBuf]) -> Result<Vec<Seen>, files::FileError> {
    let read = || paths.iter().map(|p| seen(p)).collect::<Result<Vec<_>, _>>();
    let mut bytes = read()?;
    loop {
        std::thread::sleep(SETTLE);
        let again = read()?;
        if again == bytes {
            return Ok(bytes);
        }
        bytes = again;
    }
}

/// The page the run just wrote. Read directly, not by `files::read_bounded`, which would count
/// it among the run's inputs and refuse to write it the next time.
fn read_page(path: &Path) -> Result<String, CliError> {
    std::fs::read_to_string(path).map_err(|source| CliError::File(files::FileError::Io { path: path.to_path_buf(), action: "read", source }))
}

/// 128 random bits as hex: the page's address carries them, and the server answers nothing
/// without them (another local user, or a web page guessing ports, cannot read the runs).
fn token() -> Result<String, CliError> {
    let mut bits = [0u8; 16];
    getrandom::fill(&mut bits).map_err(|e| CliError::Serve { port: 0, reason: format!("no random token: {e}") })?;
    Ok(bits.iter().map(|b| format!("{b:02x}")).collect())
}

/// The page before the first good run: the error, asked for again until a run is ready.
const WAITING: &str = r#"<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>multibody watch</title></head>
<body style="font: 14px system-ui, sans-serif; margin: 24px"><p>Waiting for the first run of the model...</p>
<pre id="problem" style="color: #8b0000; white-space: pre-wrap"></pre>
<script>
"use strict";
const token = new URLSearchParams(location.search).get("token") || "";
const poll = async () => {
  try {
    const news = await (await fetch("status?token=" + encodeURIComponent(token), { cache: "no-store" })).json();
    document.getElementById("problem").textContent = news.error || "";
    if (news.run > 0) { location.reload(); return; }
  } catch (e) {}
  setTimeout(poll, 250);
};
poll();
</script></body></html>
"#;

/// One request: `/` the page, `/status` the news (`{"run": N, "error": ...}`), with the token.
fn answer(request: tiny_http::Request, shown: &Mutex<Shown>, token: &str) {
    let url = request.url().to_string();
    let (path, query) = url.split_once('?').unwrap_or((&url, ""));
    let given = query.split('&').find_map(|kv| kv.strip_prefix("token="));
    let reply = |status: u16, kind: &str, body: String| {
        let mut response = tiny_http::Response::from_string(body).with_status_code(status);
        for (name, value) in [("Content-Type", kind), ("Cache-Control", "no-store"), ("X-Content-Type-Options", "nosniff")] {
            response.add_header(tiny_http::Header::from_bytes(name, value).expect("plain header"));
        }
        response
    };
    let response = if request.method() != &tiny_http::Method::Get {
        reply(405, "text/plain; charset=utf-8", "only GET\n".into())
    } else if given != Some(token) {
        reply(403, "text/plain; charset=utf-8", "the address needs the token the tool printed\n".into())
    } else {
        let s = shown.lock().unwrap_or_else(|p| p.into_inner());
        match path {
            "/" | "/index.html" => match s.page.as_deref() {
                Some(page) => match animate::live(page, s.run, token) {
                    Some(live) => reply(200, "text/html; charset=utf-8", live),
                    None => reply(500, "text/plain; charset=utf-8", "the page could not be made live\n".into()),
                },
                None => reply(200, "text/html; charset=utf-8", WAITING.into()),
            },
            "/status" => reply(200, "application/json", serde_json::json!({ "run": s.run, "error": s.error }).to_string()),
            _ => reply(404, "text/plain; charset=utf-8", "no such page\n".into()),
        }
    };
    // A browser that went away mid-answer is no concern of the loop's.
    let _ = request.respond(response);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small file is seen by its bytes, a large one by its size and modification time: either
    /// changes when the file is written anew, and stays when it is not.
    #[test]
    fn a_large_file_is_seen_by_its_size_and_time() {
        let dir = tempfile::tempdir().unwrap();
        let (small, large) = (dir.path().join("model.ron"), dir.path().join("mesh.stl"));
        std::fs::write(&small, "Model()").unwrap();
        std::fs::write(&large, vec![b'x'; READ_UP_TO as usize + 1]).unwrap();
        assert_eq!(seen(&small).unwrap(), Seen::Bytes(b"Model()".to_vec()));
        let before = seen(&large).unwrap();
        assert!(matches!(before, Seen::Stamp(n, Some(_)) if n == READ_UP_TO + 1), "{before:?}");
        assert_eq!(seen(&large).unwrap(), before);
        // Written again, the same size: its modification time moves on.
        let time = std::fs::metadata(&large).unwrap().modified().unwrap();
        std::fs::write(&large, vec![b'y'; READ_UP_TO as usize + 1]).unwrap();
        std::fs::File::options().write(true).open(&large).unwrap().set_modified(time + Duration::from_millis(1)).unwrap();
        assert_ne!(seen(&large).unwrap(), before);
        std::fs::write(&small, "Model(x)").unwrap();
        assert_eq!(seen(&small).unwrap(), Seen::Bytes(b"Model(x)".to_vec()));
        // A file that is gone is the loader's error.
        std::fs::remove_file(&small).unwrap();
        assert!(seen(&small).is_err());
    }
}
