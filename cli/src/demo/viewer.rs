//! `ygg demo --view`: the browser viewer (`ygg view --scene`) following the demo's scene,
//! started once the writer is ready and stopped with the demo.

use std::path::Path;
use std::time::{Duration, Instant};

use rustix::process::Signal;

use super::child::Child;
use super::scene::DemoScene;
use crate::view;

/// How long the viewer may take to show the first snapshot and serve its page.
const VIEWER_READY: Duration = Duration::from_secs(60);
/// How long the viewer may take to exit after SIGINT before it is killed.
const VIEWER_EXIT: Duration = Duration::from_secs(5);

/// The viewer process of a demo run.
pub struct DemoViewer {
    proc: Child,
}

impl DemoViewer {
    /// Starts the viewer on `scene`, serving its page on `port`, and waits for its
    /// `ready` line; returns it with the page's address.
    ///
    /// # Errors
    /// When the viewer is not installed, cannot start, or is not ready in time.
    pub fn start(
        scene: &DemoScene,
        port: u16,
    ) -> Result<(Self, String), Box<dyn std::error::Error>> {
        let python = view::python();
        view::check_installed(&python)?;
        let port = port.to_string();
        let args = [
            "-m",
            "yggdrasil.view",
            "--scene",
            &scene.name,
            "--port",
            &port,
        ];
        let mut proc = Child::start(scene.command(Path::new(&python), &args), "viewer")?;
        let until = Instant::now() + VIEWER_READY;
        while Instant::now() < until && proc.try_status().is_none() {
            let Some(line) = proc.next_line(Duration::from_millis(100)) else {
                continue;
            };
            let ready: serde_json::Value = serde_json::from_str(&line).unwrap_or_default();
            if ready["event"] == "ready" {
                let url = ready["url"].as_str().unwrap_or_default().to_owned();
                return Ok((Self { proc }, url));
            }
        }
        Err(format!("the viewer did not start:\n{}", proc.stderr_tail()).into())
    }

    /// Stops the viewer (SIGINT: it detaches from the scene), killing it if it does not
    /// exit within [`VIEWER_EXIT`].
    pub fn stop(mut self) {
        self.proc.signal(Signal::INT);
        let until = Instant::now() + VIEWER_EXIT;
        while self.proc.try_status().is_none() && Instant::now() < until {
            // A bounded poll: the child's exit has no event to wait on here.
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}
