//! `ygg record`: follows a live scene as a reader and appends each cut it receives to a
//! recording (a folder), until signalled or `--seconds` pass.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Parser;
use ygg_reader::{RecordError, SceneReader, SceneRecorder};
use ygg_store::recording::{RecordingOptions, RecordingWriter};

/// Arguments of `ygg record`.
#[derive(Parser, Debug)]
pub struct RecordArgs {
    /// The live scene to record.
    #[arg(long)]
    scene: String,
    /// The recording's folder (created if missing; an existing recording is continued
    /// in a new file).
    #[arg(long, short)]
    output: PathBuf,
    /// Keep the recording under this size by dropping its oldest files (e.g. 500M, 2G;
    /// files then hold at most a quarter of it each).
    #[arg(long, value_parser = parse_size)]
    max_size: Option<u64>,
    /// Drop files whose newest cut is older than this many seconds.
    #[arg(long)]
    max_age: Option<f64>,
    /// Stop after this many seconds; default: run until SIGINT/SIGTERM.
    #[arg(long)]
    seconds: Option<f64>,
    /// Seconds to wait for the scene's writer.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
}

/// A size with an optional K, M or G suffix (powers of 1024).
fn parse_size(s: &str) -> Result<u64, String> {
    let (digits, unit) = match s.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&s[..i], c.to_ascii_uppercase()),
        _ => (s, 'B'),
    };
    let shift = match unit {
        'B' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        _ => return Err(format!("'{s}': the unit must be K, M or G")),
    };
    digits
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(1 << shift))
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("'{s}' is not a size (a positive number, then K, M or G)"))
}

/// Runs `ygg record`.
///
/// # Errors
/// A message naming the scene or the recording's file: no writer, an append that failed
/// (the recording stays readable up to its last complete cut).
pub fn run(args: &RecordArgs) -> Result<(), String> {
    let positive = |v: Option<f64>, flag: &str| match v {
        Some(s) if !(s.is_finite() && s > 0.0) => {
            Err(format!("{flag} must be a positive number of seconds"))
        }
        _ => Ok(v),
    };
    let seconds = positive(args.seconds, "--seconds")?;
    let max_age = positive(args.max_age, "--max-age")?.map(Duration::from_secs_f64);
    let timeout = crate::query::seconds(args.timeout, "--timeout")?;
    // A file-size limit (ulimit -f) makes a write fail with EFBIG instead of killing us.
    ignore_file_size_signal();
    let reader = SceneReader::builder(&args.scene)
        .wait_for_writer(timeout)
        .handle_termination_signals(true)
        .open()
        .map_err(|e| format!("scene {}: {e}", args.scene))?;
    let options = RecordingOptions {
        max_bytes: args.max_size,
        max_age,
        ..RecordingOptions::default()
    };
    let writer = RecordingWriter::create(&args.output, options).map_err(|e| e.to_string())?;
    let mut recorder = SceneRecorder::new(reader, writer);
    println!(
        "{}",
        serde_json::json!({"event": "ready", "scene": args.scene, "output": args.output.display().to_string()})
    );
    let start = Instant::now();
    let mut last_report = start;
    let stop = loop {
        if seconds.is_some_and(|s| start.elapsed().as_secs_f64() >= s) {
            break "time limit".to_owned();
        }
        match recorder.record_next(Duration::from_millis(200)) {
            Ok(_) => {}
            Err(RecordError::Receive(ygg_reader::SceneReceiveError::Receive(
                ygg_reader::ReceiveError::Terminated,
            ))) => break "signal".to_owned(),
            Err(RecordError::Receive(e)) => {
                // A refused cut is skipped (the next one may be fine); a writer that is
                // gone is waited for, as any reader does.
                eprintln!("ygg record: {e}");
            }
            Err(RecordError::Recording(e)) => {
                summary(&recorder, start, "error");
                return Err(format!(
                    "{e} (the recording is readable up to its last cut)"
                ));
            }
        }
        if recorder.reader().termination_requested() {
            break "signal".to_owned();
        }
        if last_report.elapsed() >= Duration::from_secs(1) {
            last_report = Instant::now();
            println!(
                "{}",
                serde_json::json!({"event": "progress", "cuts": recorder.cuts_recorded(),
                    "bytes": recorder.bytes_recorded(), "seconds": start.elapsed().as_secs_f64()})
            );
        }
    };
    recorder.recording().sync().map_err(|e| e.to_string())?;
    summary(&recorder, start, &stop);
    Ok(())
}

fn summary(recorder: &SceneRecorder, start: Instant, stop: &str) {
    println!(
        "{}",
        serde_json::json!({"event": "summary", "stop": stop, "cuts": recorder.cuts_recorded(),
            "bytes": recorder.bytes_recorded(), "seconds": start.elapsed().as_secs_f64()})
    );
}

/// SIGXFSZ ignored: a write past the file-size limit then fails with EFBIG, which the
/// recorder reports, rather than killing the process.
#[allow(unsafe_code, reason = "setting a signal's disposition to ignore")]
fn ignore_file_size_signal() {
    // SAFETY: `signal` with SIG_IGN installs no handler code and touches no Rust state;
    // SIGXFSZ is raised only by a write past the file-size limit, which now fails with
    // EFBIG instead.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn sizes_take_k_m_g_suffixes_and_junk_is_refused() {
        assert_eq!(parse_size("512"), Ok(512));
        assert_eq!(parse_size("2K"), Ok(2048));
        assert_eq!(parse_size("3m"), Ok(3 << 20));
        assert_eq!(parse_size("1G"), Ok(1 << 30));
        for bad in ["", "0", "G", "12T", "-1M", "1.5G"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }
}
