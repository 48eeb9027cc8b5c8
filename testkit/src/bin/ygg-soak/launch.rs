//! Starting the processes of a soak: `ygg serve` and the demo's reader roles
//! (`ygg demo-role`), as the demo starts them, under the run's own scene.

use serde_json::Value;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use ygg_testkit::{Input, Proc, TestScene};

/// The demo's reader roles (`ygg demo-role --role ...`).
pub const ROLES: [&str; 3] = ["planner", "visibility", "labels"];

/// How long the writer may take to build the office and serve it.
pub const WRITER_READY: Duration = Duration::from_secs(120);

/// A flag that Ctrl-C (SIGINT) sets.
pub fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, ctrlc::Error> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))?;
    Ok(stop)
}

/// Starts `ygg serve` on `scene`: the built-in office at `scale`, updated `rate`
/// times a second, exiting by itself after `seconds`, with `extra` arguments.
pub fn start_writer(
    scene: &TestScene,
    rate: f64,
    scale: f64,
    seconds: f64,
    extra: &[&str],
    label: &str,
) -> std::io::Result<Proc> {
    let args = [
        "serve".to_owned(),
        "--scene".to_owned(),
        scene.name.clone(),
        "--seconds".to_owned(),
        format!("{seconds}"),
        "--rate".to_owned(),
        format!("{rate}"),
        "--scale".to_owned(),
        format!("{scale}"),
    ];
    let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
    args.extend_from_slice(extra);
    let writer_bin = ygg_testkit::binary("ygg");
    Proc::start(scene.command_for(&writer_bin, &args), label, Input::Null)
}

/// Starts the reader role `role` (`ygg demo-role`) on `scene` for
/// `seconds`, with `extra` arguments.
pub fn start_role(
    scene: &TestScene,
    role: &str,
    seconds: f64,
    extra: &[&str],
    label: &str,
) -> std::io::Result<Proc> {
    let seconds = format!("{seconds}");
    let mut args = vec![
        "demo-role",
        "--scene",
        &scene.name,
        "--role",
        role,
        "--seconds",
        &seconds,
    ];
    args.extend_from_slice(extra);
    let roles_bin = ygg_testkit::binary("ygg");
    Proc::start(scene.command_for(&roles_bin, &args), label, Input::Null)
}

/// Waits until `writer` prints its `ready` line and returns it parsed.
///
/// # Errors
/// When the writer exits first, `stop` is set, or it is not ready within
/// [`WRITER_READY`]:
/// a message with the end of its stderr.
pub fn wait_ready(writer: &mut Proc, stop: &AtomicBool) -> Result<Value, String> {
    let until = Instant::now() + WRITER_READY;
    loop {
        let seen = writer.wait_line_after(0, Duration::from_millis(100), |l| {
            l.contains("\"event\":\"ready\"")
        });
        if let Some(v) = seen.and_then(|(_, l)| serde_json::from_str(&l).ok()) {
            return Ok(v);
        }
        let why = if stop.load(Ordering::SeqCst) {
            "interrupted"
        } else if writer.try_status().is_some() {
            "it exited"
        } else if Instant::now() >= until {
            "not ready in time"
        } else {
            continue;
        };
        return Err(format!(
            "{} did not start ({why}):\n{}",
            writer.label(),
            stderr_tail(writer)
        ));
    }
}

/// The end of a process's stderr, for an error message.
pub fn stderr_tail(proc: &Proc) -> String {
    let lines = proc.stderr();
    lines[lines.len().saturating_sub(20)..].join("\n")
}
