//! `ygg inspect run.yggrec`: a recording's files, cuts and time span, and its timeline
//! (each cut's time, generation, bytes added and layers changed); with `--at`/`--time`,
//! the scene at one cut.

use std::collections::BTreeSet;
use std::path::Path;

use ygg_store::snapshot::segment_layer_part;

use crate::inspect::{InspectArgs, Memory, print_scene};
use crate::moment::{chosen_cut, open_recording};

/// Runs `ygg inspect` on a recording.
///
/// # Errors
/// A message naming the recording, a moment without a cut, or a cut that fails
/// validation.
pub fn run(path: &Path, args: &InspectArgs) -> Result<(), String> {
    let recording = open_recording(path)?;
    if args.at.is_some() || args.time.is_some() {
        let cut = chosen_cut(&recording, args.at, args.time)?;
        let raw = recording.raw_cut(cut).map_err(|e| e.to_string())?;
        let memory = Memory::of_segments(
            raw.manifest.len(),
            raw.segments.iter().map(|s| (s.id, s.bytes.len())),
        );
        let scene = recording.scene(cut).map_err(|e| e.to_string())?;
        let summary = scene.summary();
        print_scene(
            &format!(
                "recording {} cut {cut} (generation {}, {:.3} s after the first cut)",
                path.display(),
                summary.generation,
                (summary.writer_unix_ns - recording.cuts()[0].writer_unix_ns) as f64 / 1e9
            ),
            scene.view(),
            summary.generation,
            &memory,
            args.verbose,
        );
        return Ok(());
    }
    let cuts = recording.cuts();
    let (first, last) = (cuts[0], cuts[cuts.len() - 1]);
    let bytes: usize = recording.files().map(|(_, b)| b).sum();
    let sessions: BTreeSet<u64> = cuts.iter().map(|c| c.session).collect();
    println!("recording {}", path.display());
    println!(
        "  {} files, {:.2} MB; {} cuts, generations {} to {}, {} writer session(s)",
        recording.files().count(),
        bytes as f64 / 1e6,
        cuts.len(),
        first.generation,
        last.generation,
        sessions.len()
    );
    println!(
        "  from {:.3} to {:.3} s since the Unix epoch ({:.3} s)",
        first.writer_unix_ns as f64 / 1e9,
        last.writer_unix_ns as f64 / 1e9,
        (last.writer_unix_ns - first.writer_unix_ns) as f64 / 1e9
    );
    for defect in recording.defects() {
        println!("  damaged: {defect}");
    }
    let names = layer_names(&recording, cuts.len() - 1);
    let shown: Vec<usize> = if args.cuts == 0 || args.cuts >= cuts.len() {
        (0..cuts.len()).collect()
    } else {
        let head = args.cuts.div_ceil(2);
        (0..head)
            .chain(cuts.len() - (args.cuts - head)..cuts.len())
            .collect()
    };
    println!(
        "\n  {:>7} {:>12} {:>10} {:>10} {:>9}  layers changed",
        "cut", "generation", "time s", "bytes", "segments"
    );
    let mut previous_shown = None;
    for i in shown {
        if previous_shown.is_some_and(|p: usize| p + 1 != i) {
            println!("  {:>7}", "...");
        }
        previous_shown = Some(i);
        let c = cuts[i];
        let changed = changed_layers(&recording, i)?
            .into_iter()
            .map(|l| {
                names
                    .get(&l)
                    .cloned()
                    .unwrap_or_else(|| format!("layer {l}"))
            })
            .collect::<Vec<_>>()
            .join(", ");
        println!(
            "  {:>7} {:>12} {:>10.3} {:>10} {:>9}  {}",
            i,
            c.generation,
            (c.writer_unix_ns - first.writer_unix_ns) as f64 / 1e9,
            c.bytes_added,
            c.segments_added,
            if i == 0 {
                "(all: first cut)".to_owned()
            } else {
                changed
            }
        );
    }
    Ok(())
}

/// Layer id -> name, from cut `cut`'s scene.
fn layer_names(
    recording: &ygg_store::recording::Recording,
    cut: usize,
) -> std::collections::BTreeMap<u32, String> {
    use ygg_store::SceneView;
    recording.scene(cut).map_or_else(
        |_| Default::default(),
        |s| {
            let v = s.view();
            v.layers()
                .map(|l| (l.0, v.layer_name(l).unwrap_or_default().to_owned()))
                .collect()
        },
    )
}

/// The ids of the layers whose segments differ between cut `cut` and the one before.
fn changed_layers(
    recording: &ygg_store::recording::Recording,
    cut: usize,
) -> Result<BTreeSet<u32>, String> {
    if cut == 0 {
        return Ok(BTreeSet::new());
    }
    let err = |e: ygg_store::recording::RecordingError| e.to_string();
    let now: BTreeSet<_> = recording.segments(cut).map_err(err)?.into_iter().collect();
    let before: BTreeSet<_> = recording
        .segments(cut - 1)
        .map_err(err)?
        .into_iter()
        .collect();
    Ok(now
        .symmetric_difference(&before)
        .filter_map(|(id, _)| segment_layer_part(*id).map(|(l, _)| l.0))
        .collect())
}
