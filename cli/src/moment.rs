//! Naming a moment of a recording on the command line: a time (`--time`, `--from`,
//! `--to`) or a generation (`--at`), resolved to a recorded cut.

use ygg_store::recording::Recording;

/// A time given on the command line: seconds since the Unix epoch (`1733490000.5`),
/// seconds after the recording's first cut (`+12.5`), or before its last (`-30`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeSpec {
    /// Seconds since the Unix epoch (the writer's clock).
    Unix(f64),
    /// Seconds after the first cut.
    AfterFirst(f64),
    /// Seconds before the last cut.
    BeforeLast(f64),
}

impl std::str::FromStr for TimeSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let number = |t: &str| {
            t.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    format!(
                        "'{s}' is not a time: give seconds since the Unix epoch, +S after the \
                         first cut or -S before the last"
                    )
                })
        };
        match s.as_bytes().first() {
            Some(b'+') => number(&s[1..]).map(TimeSpec::AfterFirst),
            Some(b'-') => number(&s[1..]).map(TimeSpec::BeforeLast),
            _ => number(s).map(TimeSpec::Unix),
        }
    }
}

impl TimeSpec {
    /// The time in ns since the Unix epoch, for `recording`.
    pub fn unix_ns(self, recording: &Recording) -> u64 {
        let cuts = recording.cuts();
        let ns = |s: f64| (s * 1e9) as u64;
        match self {
            TimeSpec::Unix(s) => ns(s),
            TimeSpec::AfterFirst(s) => cuts[0].writer_unix_ns.saturating_add(ns(s)),
            TimeSpec::BeforeLast(s) => cuts[cuts.len() - 1].writer_unix_ns.saturating_sub(ns(s)),
        }
    }

    /// The cut the scene was in at this time: the last one published at or before it.
    ///
    /// # Errors
    /// A message when the time is before the first cut.
    pub fn cut(self, recording: &Recording) -> Result<usize, String> {
        let t = self.unix_ns(recording);
        recording.cut_at_time(t).ok_or_else(|| {
            format!(
                "{}: no cut at or before {:.3} s since the Unix epoch; the first is at {:.3}",
                recording.dir().display(),
                t as f64 / 1e9,
                recording.cuts()[0].writer_unix_ns as f64 / 1e9
            )
        })
    }
}

/// The cut named by `--at GENERATION` or `--time T` (the last cut when neither is given).
///
/// # Errors
/// A message naming the recording when no cut matches.
pub fn chosen_cut(
    recording: &Recording,
    generation: Option<u64>,
    time: Option<TimeSpec>,
) -> Result<usize, String> {
    match (generation, time) {
        (Some(g), _) => recording.cut_at_generation(g).ok_or_else(|| {
            format!(
                "{}: no cut of generation {g} or earlier; the first is {}",
                recording.dir().display(),
                recording.cuts()[0].generation
            )
        }),
        (None, Some(t)) => t.cut(recording),
        (None, None) => Ok(recording.cuts().len() - 1),
    }
}

/// Whether `path` is a recording's folder (rather than a `.ygg` or Spark-DSG file).
pub fn is_recording(path: &std::path::Path) -> bool {
    path.is_dir()
}

/// Opens a recording, warning on stderr about damage found in its files.
///
/// # Errors
/// The recording's error, naming the folder or file.
pub fn open_recording(path: &std::path::Path) -> Result<Recording, String> {
    let recording = Recording::open(path).map_err(|e| e.to_string())?;
    for defect in recording.defects() {
        eprintln!("ygg: warning: {defect}");
    }
    Ok(recording)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_parse_as_absolute_or_relative_and_junk_is_refused() {
        assert_eq!("12.5".parse(), Ok(TimeSpec::Unix(12.5)));
        assert_eq!("+3".parse(), Ok(TimeSpec::AfterFirst(3.0)));
        assert_eq!("-0.5".parse(), Ok(TimeSpec::BeforeLast(0.5)));
        for bad in ["", "+", "abc", "+-1", "nan", "inf", "1e400"] {
            assert!(bad.parse::<TimeSpec>().is_err(), "{bad}");
        }
    }
}
