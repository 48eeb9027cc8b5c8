//! Finding (and building once) the workspace's executables and examples.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// Env var naming a directory that holds prebuilt `ygg-writer` / `ygg-reader` /
/// `ygg-bench` binaries (examples in its `examples/` folder).
pub const ENV_BIN_DIR: &str = "YGG_BIN_DIR";

/// Path of the workspace binary `name` (`ygg-writer`, `ygg-reader` or `ygg-bench`).
///
/// Binaries of other packages are not exposed to this package by cargo
/// (`CARGO_BIN_EXE_*` is per package), so the harness takes them from [`ENV_BIN_DIR`] if set,
/// else from the profile directory of the running executable
/// (`target/<profile>/deps/ipc-…` -> `target/<profile>/`). When run by cargo, it first runs
/// `cargo build -p ygg-writer -p ygg-reader -p ygg-bench --bins` for that profile and target
/// directory once (a no-op when they are up to date; cargo releases its lock while tests
/// and `cargo run` binaries run).
///
/// # Panics
///
/// If the binary cannot be found or built.
pub fn binary(name: &str) -> PathBuf {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    let dir = BUILT.get_or_init(|| {
        located(&[
            "-p",
            "ygg-writer",
            "-p",
            "ygg-reader",
            "-p",
            "ygg-bench",
            "--bins",
        ])
    });
    existing(dir.join(name))
}

/// Path of the example `name` of `ygg-examples` (`target/<profile>/examples/<name>`),
/// found and built like [`binary`] (`cargo build -p ygg-examples --examples`).
///
/// # Panics
///
/// If the example cannot be found or built.
pub fn example(name: &str) -> PathBuf {
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    let dir = BUILT.get_or_init(|| located(&["-p", "ygg-examples", "--examples"]));
    existing(dir.join("examples").join(name))
}

fn existing(path: PathBuf) -> PathBuf {
    assert!(
        path.is_file(),
        "{} not found; build it (cargo build --workspace --bins --examples) or set {ENV_BIN_DIR}",
        path.display()
    );
    path
}

/// The directory of prebuilt binaries, or the profile directory of this executable after
/// `cargo build <what>` there (when run by cargo).
fn located(what: &[&str]) -> PathBuf {
    if let Some(dir) = std::env::var_os(ENV_BIN_DIR) {
        return PathBuf::from(dir);
    }
    let exe = std::env::current_exe().expect("path of the running executable");
    let dir = exe.parent().expect("an executable lives in a directory");
    let profile_dir = if dir.ends_with("deps") || dir.ends_with("examples") {
        dir.parent().expect("deps has a parent")
    } else {
        dir
    };
    if let Some(cargo) = std::env::var_os("CARGO") {
        cargo_build(Path::new(&cargo), profile_dir, what);
    }
    profile_dir.to_owned()
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
