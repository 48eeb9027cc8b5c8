//! `ygg serve --recording`: republishes a recording's cuts as a live scene with their
//! recorded timing ([`RecordingPlayer`]).

use std::path::Path;

use ygg_transport::PublisherBuilder;
use ygg_writer::{PlayOptions, RecordingPlayer, ReplayError};

use crate::moment::{TimeSpec, open_recording};

/// How `ygg serve --recording` plays.
pub struct ReplayArgs<'a> {
    /// The scene name to publish under.
    pub scene: &'a str,
    /// The recording's folder.
    pub recording: &'a Path,
    /// Playback speed.
    pub speed: f64,
    /// Where to start.
    pub from: Option<TimeSpec>,
    /// Play again from the start after the last cut.
    pub looped: bool,
    /// Readers the scene supports at once.
    pub max_readers: usize,
    /// Stop after this many seconds.
    pub seconds: Option<f64>,
}

/// Plays the recording, then keeps serving its last cut (as `ygg serve` serves its scene)
/// until SIGINT/SIGTERM or `--seconds`; prints `ready`, `progress` (each second), `end`
/// (the last cut went out) and `summary` lines.
///
/// # Errors
/// A message naming the recording or the scene.
pub fn run(args: &ReplayArgs<'_>) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.speed.is_finite() && args.speed > 0.0) {
        return Err("--speed must be a positive number".into());
    }
    let recording = open_recording(args.recording)?;
    let from_cut = match args.from {
        Some(t) => t.cut(&recording)?,
        None => 0,
    };
    let cuts = recording.cuts().len();
    let publisher = PublisherBuilder::new(args.scene).max_readers(args.max_readers);
    let mut player = RecordingPlayer::new(recording, publisher)?;
    println!(
        "{}",
        serde_json::json!({"event": "ready", "scene": args.scene, "session": player.publisher().session(),
            "recording": args.recording.display().to_string(), "cuts": cuts, "from_cut": from_cut})
    );
    let start = std::time::Instant::now();
    let mut last_report = start;
    let mut played = 0u64;
    let options = PlayOptions {
        speed: args.speed,
        from_cut,
        looped: args.looped,
    };
    let result = player.play(options, |cut| {
        played += 1;
        let more = args
            .seconds
            .is_none_or(|s| start.elapsed().as_secs_f64() < s);
        if last_report.elapsed().as_secs_f64() >= 1.0 {
            last_report = std::time::Instant::now();
            println!(
                "{}",
                serde_json::json!({"event": "progress", "cut": cut, "cuts_played": played,
                    "seconds": start.elapsed().as_secs_f64()})
            );
        }
        more
    });
    let stop = match result {
        Ok(_)
            if args
                .seconds
                .is_some_and(|s| start.elapsed().as_secs_f64() >= s) =>
        {
            "time limit".to_owned()
        }
        // As a live writer would, keep serving the last cut until signalled (or
        // --seconds), so that late readers still get the scene.
        Ok(_) => {
            println!(
                "{}",
                serde_json::json!({"event": "end", "cuts_played": played, "generation": player.generation()})
            );
            serve_last_cut(&player, start, args.seconds)
        }
        Err(ReplayError::Interrupted(e)) => e.to_string(),
        Err(e) => return Err(e.into()),
    };
    let late: Vec<f64> = player
        .lateness()
        .iter()
        .map(|d| d.as_secs_f64() * 1e3)
        .collect();
    // How far each interval between two cuts strayed from the recorded one.
    let mut interval_error: Vec<f64> = late.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    interval_error.sort_by(f64::total_cmp);
    let pct = |v: &[f64], p: f64| {
        v.get(((v.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    println!(
        "{}",
        serde_json::json!({"event": "summary", "stop": stop, "cuts_played": played,
            "seconds": start.elapsed().as_secs_f64(), "generation": player.generation(),
            "interval_error_ms_p50": pct(&interval_error, 0.5),
            "interval_error_ms_p99": pct(&interval_error, 0.99),
            "interval_error_ms_max": pct(&interval_error, 1.0)})
    );
    Ok(())
}

/// Keeps the last cut published until SIGINT/SIGTERM or until `seconds` after `start`;
/// the reason it stopped.
fn serve_last_cut(
    player: &RecordingPlayer,
    start: std::time::Instant,
    seconds: Option<f64>,
) -> String {
    loop {
        let left = seconds.map_or(1.0, |s| (s - start.elapsed().as_secs_f64()).min(1.0));
        if left <= 0.0 {
            return "time limit".to_owned();
        }
        if let Err(e) = player
            .publisher()
            .wait(std::time::Duration::from_secs_f64(left))
        {
            return e.to_string();
        }
    }
}
