//! Finding (and building once) the workspace's executables and examples.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// Env var naming a directory that holds prebuilt `ygg` / `ygg-relay` / `ygg-bench` /
/// `ygg-test-writer` / `ygg-test-reader` / `ygg-soak` binaries (examples in its
/// `examples/` folder).
pub const ENV_BIN_DIR: &str = "YGG_BIN_DIR";

/// Path of the workspace binary `name`: `ygg` (the command line, `ygg-cli`), `ygg-relay`,
/// `ygg-bench`, or a test driver of this crate (`ygg-test-writer`, `ygg-test-reader`,
/// `ygg-soak`).
///
/// Binaries of other packages are not exposed to this package by cargo
/// (`CARGO_BIN_EXE_*` is per package), so the harness takes them from [`ENV_BIN_DIR`] if set,
/// else from the profile directory of the running executable
/// (`target/<profile>/deps/ipc-…` -> `target/<profile>/`). When run by cargo, it first builds
/// them once for that profile and target directory, with the features the running
/// executable was compiled with, so that only the binaries' final link can be new (cargo
/// releases its lock while tests and `cargo run` binaries run): a tool run by cargo
/// (`cargo run -p ygg-bench`, `cargo run -p ygg-testkit --bin ygg-soak`) runs
/// `cargo build -p ygg-cli -p ygg-bench -p ygg-testkit --bins`, a test (and a tool a test
/// starts) `cargo build --workspace --bins --examples --tests` (what
/// `cargo test --workspace` compiled).
///
/// # Panics
///
/// If the binary cannot be found or built.
pub fn binary(name: &str) -> PathBuf {
    existing(built_profile_dir().join(name))
}

/// Path of the example `name` of `ygg-examples` (`target/<profile>/examples/<name>`),
/// found and built like [`binary`].
///
/// # Panics
///
/// If the example cannot be found or built.
pub fn example(name: &str) -> PathBuf {
    existing(built_profile_dir().join("examples").join(name))
}

fn existing(path: PathBuf) -> PathBuf {
    assert!(
        path.is_file(),
        "{} not found; build it (cargo build --workspace --bins --examples --tests) or set {ENV_BIN_DIR}",
        path.display()
    );
    path
}

/// What a test (an executable in `target/<profile>/deps/`) builds: the whole workspace with
/// its tests. Cargo unifies features over the packages and targets it builds, so this is the
/// feature set `cargo test --workspace` has just compiled with. A narrower selection would
/// resolve other features and compile every dependency a second time (minutes on two cores
/// and gigabytes in `target/`).
const FROM_A_TEST: [&str; 4] = ["--workspace", "--bins", "--examples", "--tests"];

/// What a tool run by cargo (a bench or the soak) builds: the executables it starts.
const FROM_A_TOOL: [&str; 7] = [
    "-p",
    "ygg-cli",
    "-p",
    "ygg-bench",
    "-p",
    "ygg-testkit",
    "--bins",
];

/// The packages whose binaries are tools that start other workspace binaries.
const TOOLS: [&str; 2] = ["ygg-bench", "ygg-testkit"];

/// The directory of prebuilt binaries ([`ENV_BIN_DIR`]), or the profile directory of this
/// executable after the `cargo build` above there (when run by cargo); built once.
fn built_profile_dir() -> &'static Path {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    BUILT.get_or_init(|| {
        if let Some(dir) = std::env::var_os(ENV_BIN_DIR) {
            return PathBuf::from(dir);
        }
        let exe = std::env::current_exe().expect("path of the running executable");
        let dir = exe.parent().expect("an executable lives in a directory");
        let from_a_test = dir.ends_with("deps") || dir.ends_with("examples");
        let profile_dir = if from_a_test {
            dir.parent().expect("deps has a parent")
        } else {
            dir
        };
        if let Some(cargo) = std::env::var_os("CARGO") {
            // `cargo run -p ygg-bench` sets CARGO_PKG_NAME to ygg-bench; a tool a test starts
            // inherits the test's (and the test has built the workspace's set).
            let run_as_a_tool = !from_a_test
                && std::env::var("CARGO_PKG_NAME").is_ok_and(|name| TOOLS.contains(&name.as_str()));
            let what: &[&str] = if run_as_a_tool {
                &FROM_A_TOOL
            } else {
                &FROM_A_TEST
            };
            cargo_build(Path::new(&cargo), profile_dir, what);
        }
        profile_dir.to_owned()
    })
}

fn cargo_build(cargo: &Path, profile_dir: &Path, what: &[&str]) {
    let Some(target_dir) = profile_dir.parent() else {
        return;
    };
    let mut command = Command::new(cargo);
    command.arg("build").args(what);
    match profile_dir.file_name().and_then(|n| n.to_str()) {
        Some("debug") | None => {}
        Some("release") => {
            command.arg("--release");
        }
        Some(profile) => {
            command.args(["--profile", profile]);
        }
    }
    command.env("CARGO_TARGET_DIR", target_dir);
    if let Ok(manifest_dir) = std::env::var("CARGO_MANIFEST_DIR") {
        command.current_dir(manifest_dir);
    }
    let output = command.output().expect("run cargo build");
    assert!(
        output.status.success(),
        "cargo build {} failed:\n{}",
        what.join(" "),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Runs executable `name` ([`binary`]) with `args` to completion, stdin `/dev/null`,
/// iceoryx2's log level left to its default.
///
/// # Panics
/// If the process cannot be started.
pub fn run(name: &str, args: &[&dyn AsRef<std::ffi::OsStr>]) -> std::process::Output {
    std::process::Command::new(binary(name))
        .args(args.iter().map(|a| -> &std::ffi::OsStr { (*a).as_ref() }))
        .env_remove("IOX2_LOG_LEVEL")
        .stdin(std::process::Stdio::null())
        .output()
        .expect("spawn")
}

/// Process output as text (lossy UTF-8).
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}
