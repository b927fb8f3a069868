//! Pinocchio beside us, outside CI: the `pin` wheel (Pinocchio's headers and library) and
//! Eigen's headers installed into a virtual environment under `target/peers/`, and
//! `benches/pinocchio/aba.cpp` built against them with `g++ -O3 -march=native`, header-only
//! (every template instantiated for this machine). Shared (`#[path]`) by the Pinocchio
//! benchmark of the generator and the robots' benchmark of the workspace.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The `pin` wheel's version (Pinocchio 4.1), the Eigen headers it builds with and the robots
/// of `example-robot-data`.
const PIN: &str = "pin==4.1.0";
const EIGEN: &str = "cmeel-eigen==3.4.1";
const ROBOTS: &str = "example-robot-data==6.0.0";

/// The compile definitions Pinocchio's CMake package gives its users (Boost's variant of 25
/// joint kinds), without `PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION`: every template is
/// instantiated here, for this machine.
const DEFINES: [&str; 4] =
    ["-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30", "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "-DBOOST_FUSION_INVOKE_MAX_ARITY=12"];

/// A file of `generator/benches/pinocchio/`, from the generator's package or the workspace's.
fn bench_file(name: &str) -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    [manifest.join("benches/pinocchio").join(name), manifest.join("generator/benches/pinocchio").join(name)]
        .into_iter()
        .find(|p| p.exists())
        .unwrap_or_else(|| panic!("generator/benches/pinocchio/{name}"))
}

pub fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(out.status.success(), "{what} failed:\n{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The peers' virtual environment: its folder and its Python.
pub struct Peers {
    pub dir: PathBuf,
    pub python: PathBuf,
}

impl Peers {
    /// `target/peers/` of the workspace at `root`, its environment created once.
    pub fn new(root: &Path) -> Peers {
        let dir = root.join("target/peers");
        std::fs::create_dir_all(&dir).expect("target/peers");
        let venv = dir.join("venv");
        let python = venv.join("bin/python3");
        if !python.exists() {
            eprintln!("pinocchio: creating {} ...", venv.display());
            run(Command::new("python3").args(["-m", "venv"]).arg(&venv), "python3 -m venv");
        }
        Peers { dir, python }
    }

    /// The `cmeel` prefix of the environment, where the wheels put headers, libraries and data.
    fn prefix(&self) -> Option<PathBuf> {
        let out = Command::new(&self.python)
            .args(["-c", "import cmeel, os; print(os.path.join(os.path.dirname(cmeel.__path__[0]), 'cmeel.prefix'))"])
            .output()
            .ok()?;
        Some(PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
    }

    /// The `pin` wheel's prefix (headers and libraries), installed once.
    pub fn pinocchio_prefix(&self) -> PathBuf {
        self.installed(|| self.prefix().filter(|p| p.join("include/pinocchio/algorithm/aba.hpp").exists() && p.join("include/eigen3").exists()), &[PIN, EIGEN])
    }

    /// `example-robot-data`'s robots folder, installed once.
    pub fn robots_folder(&self) -> PathBuf {
        self.installed(|| self.prefix().map(|p| p.join("share/example-robot-data/robots")).filter(|p| p.is_dir()), &[PIN, ROBOTS])
    }

    /// What `ready` finds, after `pip install packages` where it finds nothing.
    fn installed(&self, ready: impl Fn() -> Option<PathBuf>, packages: &[&str]) -> PathBuf {
        if let Some(p) = ready() {
            return p;
        }
        eprintln!("pinocchio: pip install {} ...", packages.join(" "));
        run(Command::new(&self.python).args(["-m", "pip", "install", "--quiet"]).args(packages), "pip install");
        ready().unwrap_or_else(|| panic!("pip install {} did not install what the benchmark needs", packages.join(" ")))
    }

    /// `aba.cpp` built against the wheel, once per change of the source.
    pub fn aba(&self) -> PathBuf {
        let prefix = self.pinocchio_prefix();
        let source = bench_file("aba.cpp");
        let exe = self.dir.join("aba");
        let stale = |exe: &Path| -> Option<bool> { Some(std::fs::metadata(exe).ok()?.modified().ok()? < std::fs::metadata(&source).ok()?.modified().ok()?) };
        if stale(&exe) != Some(false) {
            eprintln!("pinocchio: g++ -O3 -march=native aba.cpp (about two minutes) ...");
            let (include, lib) = (prefix.join("include"), prefix.join("lib"));
            run(
                Command::new("g++")
                    .args(["-O3", "-march=native", "-DNDEBUG", "-std=c++17"])
                    .args(DEFINES)
                    .arg(format!("-I{}", include.display()))
                    .arg(format!("-I{}", include.join("eigen3").display()))
                    .arg(&source)
                    .arg(format!("-L{}", lib.display()))
                    .args(["-lpinocchio_default", "-lboost_serialization"])
                    .arg(format!("-Wl,-rpath,{}", lib.display()))
                    .arg("-o")
                    .arg(&exe),
                "g++ aba.cpp",
            );
        }
        exe
    }

    /// A robot as Pinocchio's own parser reads its URDF (`base`: `fixed` or `floating`),
    /// saved for `aba saved` (`benches/pinocchio/save_robot.py`).
    pub fn save_robot(&self, urdf: &Path, base: &str, name: &str) -> PathBuf {
        self.pinocchio_prefix();
        let script = bench_file("save_robot.py");
        let out = self.dir.join(format!("{name}-{base}.txt"));
        run(Command::new(&self.python).arg(script).arg(urdf).arg(base).arg(&out), "save_robot.py");
        out
    }
}
