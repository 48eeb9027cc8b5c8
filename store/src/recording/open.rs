//! [`Recording`]: a recording's files mapped, their records scanned once, and any cut
//! joined in place on demand ([`RecordedScene`]).

#![allow(
    unsafe_code,
    reason = "memory-mapping recording files and re-deriving archives validated before"
)]

use super::error::RecordingError;
use super::files::list_files;
use super::format::{
    CutEntry, CutList, FIRST_RECORD_AT, RECORD_HEADER_LEN, RecordDefect, RecordHeader, RecordKind,
    cut_list_at, next_record_at, read_file_header,
};
use crate::SnapshotError;
use crate::snapshot::{
    ArchivedScene, FORMAT_VERSION, chunk_unchecked, is_chunk_segment_id, is_structure_segment_id,
    is_tree_chunk_segment_id, layer_unchecked, structure_unchecked, tree_chunk_unchecked,
    validate_chunk, validate_layer, validate_manifest, validate_structure, validate_tree_chunk,
};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// One recorded cut: when it was published and recorded, and what it added to the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CutSummary {
    /// The cut's generation (as the writer numbered it).
    pub generation: u64,
    /// The writer session that published it.
    pub session: u64,
    /// When the writer began publishing it (ns since the Unix epoch, writer's clock).
    pub writer_unix_ns: u64,
    /// When the recorder appended it (ns since the Unix epoch, recorder's clock).
    pub recorder_unix_ns: u64,
    /// Segments first recorded with this cut (the ones that changed, or every one for
    /// the first cut of a file).
    pub segments_added: u32,
    /// Segments the cut names.
    pub segments: u32,
    /// Bytes the cut added to the recording: its new segments' records and its own.
    pub bytes_added: u64,
}

/// Where a cut is in the files and how its segment list is found.
struct CutInfo {
    summary: CutSummary,
    file: usize,
    /// Offset of the cut record's payload (the manifest) in its file.
    payload: usize,
    manifest_len: usize,
    list: std::ops::Range<usize>,
    /// The cut (in `cuts`) whose list names every segment, from which this cut's list
    /// follows by the lists of the cuts between.
    checkpoint: usize,
}

/// A mapped file of the recording.
struct MappedFile {
    path: PathBuf,
    map: memmap2::Mmap,
    /// Offset of each segment record's header -> its id, generation and payload range.
    segments: HashMap<u64, SegmentRecord>,
}

/// A segment record found by the scan.
struct SegmentRecord {
    id: u64,
    generation: u64,
    payload: std::ops::Range<usize>,
}

/// What a [`Recording`] holds: the mapped files, the cuts, and which recorded segments
/// passed validation.
struct RecordingData {
    dir: PathBuf,
    files: Vec<MappedFile>,
    cuts: Vec<CutInfo>,
    summaries: Vec<CutSummary>,
    defects: Vec<String>,
    /// `(file, record offset)` of every segment that passed its validation.
    validated: Mutex<HashSet<(usize, u64)>>,
}

/// A recording opened for queries: every complete cut of its files, each opened in place
/// ([`Recording::scene`]) by mapping only the segments it names. Cheap to clone.
///
/// Files are scanned once at [`Recording::open`] (record headers and CRCs); a torn tail
/// (a recorder killed while appending) is ignored, as is anything after a damaged record
/// (listed in [`Recording::defects`]). Segments are validated the first time a cut names
/// them, then trusted for later cuts.
#[derive(Clone)]
pub struct Recording {
    data: Arc<RecordingData>,
}

impl std::fmt::Debug for Recording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recording")
            .field("dir", &self.data.dir)
            .field("cuts", &self.data.cuts.len())
            .finish_non_exhaustive()
    }
}

impl Recording {
    /// Opens the recording in folder `dir`: maps its files and scans their records.
    ///
    /// # Errors
    /// [`RecordingError::Io`] when the folder or a file cannot be read,
    /// [`RecordingError::Format`] for a file that is not a recording's, and
    /// [`RecordingError::Empty`] when no complete cut is in it.
    pub fn open(dir: impl AsRef<Path>) -> Result<Recording, RecordingError> {
        let dir = dir.as_ref().to_path_buf();
        let listed = list_files(&dir)?;
        let mut data = RecordingData {
            dir: dir.clone(),
            files: Vec::with_capacity(listed.len()),
            cuts: Vec::new(),
            summaries: Vec::new(),
            defects: Vec::new(),
            validated: Mutex::new(HashSet::new()),
        };
        for listed in listed {
            let io = |source| RecordingError::Io {
                path: listed.path.display().to_string(),
                source,
            };
            let file = std::fs::File::open(&listed.path).map_err(io)?;
            // SAFETY: a read-only private map. Recording files are append-only: a recorder
            // writes past their end and cuts off only bytes of a cut it had not completed,
            // which lie past every complete cut scanned below; dropping a file unlinks it
            // (the map keeps its pages). A process that rewrites a file in place breaks
            // this contract, as for any mmap-based reader (see `SnapshotFile::open`).
            let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
            if map.is_empty() {
                // Created, then the recorder stopped before its header was written.
                continue;
            }
            let number = read_file_header(&map, FORMAT_VERSION).map_err(|reason| {
                RecordingError::Format {
                    path: listed.path.display().to_string(),
                    reason,
                }
            })?;
            if number != listed.number {
                return Err(RecordingError::Format {
                    path: listed.path.display().to_string(),
                    reason: format!("the file's header numbers it {number}"),
                });
            }
            let mut mapped = MappedFile {
                path: listed.path,
                map,
                segments: HashMap::new(),
            };
            scan(
                &mut mapped,
                data.files.len(),
                &mut data.cuts,
                &mut data.defects,
            );
            data.files.push(mapped);
        }
        if data.cuts.is_empty() {
            return Err(RecordingError::Empty {
                path: dir.display().to_string(),
            });
        }
        data.summaries = data.cuts.iter().map(|c| c.summary).collect();
        Ok(Recording {
            data: Arc::new(data),
        })
    }

    /// The recording's folder.
    pub fn dir(&self) -> &Path {
        &self.data.dir
    }

    /// Every complete cut, in recording order.
    pub fn cuts(&self) -> &[CutSummary] {
        &self.data.summaries
    }

    /// Damage found when the files were scanned (a record whose CRC does not match, ...):
    /// the cuts after it in its file are not readable. A torn tail is not listed.
    pub fn defects(&self) -> &[String] {
        &self.data.defects
    }

    /// The files of the recording and their sizes in bytes.
    pub fn files(&self) -> impl Iterator<Item = (&Path, usize)> {
        self.data
            .files
            .iter()
            .map(|f| (f.path.as_path(), f.map.len()))
    }

    /// The cut the scene was in at `unix_ns` (writer's clock): the last cut published at
    /// or before it (Khronos' "nearest snapshot at or before t"). `None` before the first.
    pub fn cut_at_time(&self, unix_ns: u64) -> Option<usize> {
        let after = self
            .data
            .summaries
            .partition_point(|c| c.writer_unix_ns <= unix_ns);
        after.checked_sub(1)
    }

    /// The last cut whose generation is at most `generation` (the exact cut when it was
    /// recorded). `None` when every cut is newer.
    pub fn cut_at_generation(&self, generation: u64) -> Option<usize> {
        self.data
            .summaries
            .iter()
            .rposition(|c| c.generation <= generation)
    }

    /// Cut `cut` (an index into [`Recording::cuts`]) as a scene queried in place.
    ///
    /// # Errors
    /// [`RecordingError::NoSuchCut`] for an index past the last cut; a segment that fails
    /// validation gives [`RecordingError::Snapshot`] naming the file and the offset.
    pub fn scene(&self, cut: usize) -> Result<RecordedScene, RecordingError> {
        self.check_cut(cut)?;
        let owner = RecordedCut {
            data: Arc::clone(&self.data),
            cut,
        };
        let cell = RecordedCell::try_new(owner, |owner| owner.data.join(owner.cut))?;
        Ok(RecordedScene { cell })
    }

    /// The raw bytes of cut `cut`: its manifest and every segment it names, ascending by
    /// id, as recorded (not validated: see [`Recording::scene`]).
    ///
    /// # Errors
    /// [`RecordingError::NoSuchCut`] for an index past the last cut.
    pub fn raw_cut(&self, cut: usize) -> Result<RawCut<'_>, RecordingError> {
        self.check_cut(cut)?;
        let info = &self.data.cuts[cut];
        let file = &self.data.files[info.file];
        let segments = self
            .data
            .entries(cut)?
            .into_iter()
            .map(|e| {
                Ok(RawSegment {
                    id: e.segment,
                    generation: e.generation,
                    bytes: self.data.payload(info.file, e)?,
                })
            })
            .collect::<Result<_, RecordingError>>()?;
        Ok(RawCut {
            summary: info.summary,
            manifest: &file.map[info.payload..info.payload + info.manifest_len],
            segments,
        })
    }

    /// The `(segment id, generation)` of every segment cut `cut` names, ascending by id.
    ///
    /// # Errors
    /// [`RecordingError::NoSuchCut`] for an index past the last cut.
    pub fn segments(&self, cut: usize) -> Result<Vec<(u64, u64)>, RecordingError> {
        self.check_cut(cut)?;
        Ok(self
            .data
            .entries(cut)?
            .into_iter()
            .map(|e| (e.segment, e.generation))
            .collect())
    }

    fn check_cut(&self, cut: usize) -> Result<(), RecordingError> {
        if cut >= self.data.cuts.len() {
            return Err(RecordingError::NoSuchCut(format!(
                "{}: no cut {cut}; the recording holds {} cuts",
                self.data.dir.display(),
                self.data.cuts.len()
            )));
        }
        Ok(())
    }
}

/// A recorded cut's bytes (see [`Recording::raw_cut`]).
#[derive(Debug, Clone)]
pub struct RawCut<'a> {
    /// When and by whom it was published.
    pub summary: CutSummary,
    /// The store's manifest bytes.
    pub manifest: &'a [u8],
    /// Every segment, ascending by id.
    pub segments: Vec<RawSegment<'a>>,
}

/// One segment of a [`RawCut`].
#[derive(Debug, Clone, Copy)]
pub struct RawSegment<'a> {
    /// The segment id.
    pub id: u64,
    /// Its generation.
    pub generation: u64,
    /// Its archived bytes (128-byte aligned).
    pub bytes: &'a [u8],
}

/// What a [`RecordedScene`] keeps alive: the recording and which cut.
struct RecordedCut {
    data: Arc<RecordingData>,
    cut: usize,
}

self_cell::self_cell!(
    /// A cut and the view joined over its mapped segments.
    struct RecordedCell {
        owner: RecordedCut,
        #[covariant]
        dependent: ArchivedScene,
    }
);

/// One cut of a [`Recording`], joined once and queried in place: every query of the
/// store runs on [`RecordedScene::view`]. Keeps the recording's files mapped.
pub struct RecordedScene {
    cell: RecordedCell,
}

impl RecordedScene {
    /// The scene as a [`crate::SceneView`].
    pub fn view(&self) -> &ArchivedScene<'_> {
        self.cell.borrow_dependent()
    }

    /// The cut's index in [`Recording::cuts`].
    pub fn index(&self) -> usize {
        self.cell.borrow_owner().cut
    }

    /// When and by whom the cut was published.
    pub fn summary(&self) -> CutSummary {
        let owner = self.cell.borrow_owner();
        owner.data.summaries[owner.cut]
    }
}

impl RecordingData {
    /// The entries of cut `cut`: its checkpoint's list with every later list applied.
    fn entries(&self, cut: usize) -> Result<Vec<CutEntry>, RecordingError> {
        let info = &self.cuts[cut];
        let mut entries = BTreeMap::new();
        for c in &self.cuts[info.checkpoint..=cut] {
            let file = &self.files[c.file];
            let list = CutList::decode(&file.map[c.list.clone()])
                .expect("every list decoded when the file was scanned");
            for id in list.removed {
                entries.remove(&id);
            }
            entries.extend(list.set.into_iter().map(|e| (e.segment, e)));
        }
        Ok(entries.into_values().collect())
    }

    /// The payload of the segment record `entry` names in file `file` (checked when
    /// the file was scanned).
    fn payload(&self, file: usize, entry: CutEntry) -> Result<&[u8], RecordingError> {
        let f = &self.files[file];
        f.segments
            .get(&entry.record)
            .map(|r| &f.map[r.payload.clone()])
            .ok_or_else(|| RecordingError::Format {
                path: format!("{} at byte {}", f.path.display(), entry.record),
                reason: "a cut names a segment record that is not there".into(),
            })
    }

    /// Validates what cut `cut` names that no earlier call validated, and joins it.
    fn join(&self, cut: usize) -> Result<ArchivedScene<'_>, RecordingError> {
        let info = &self.cuts[cut];
        let file = &self.files[info.file];
        let at = |offset: usize| format!("{} at byte {offset}", file.path.display());
        let manifest = validate_manifest(
            &file.map[info.payload..info.payload + info.manifest_len],
            &at(info.payload - RECORD_HEADER_LEN),
        )?;
        let mut structure = None;
        let (mut parts, mut chunks, mut trees) = (Vec::new(), Vec::new(), Vec::new());
        let mut validated = self.validated.lock().unwrap_or_else(|e| e.into_inner());
        for entry in self.entries(cut)? {
            let bytes = self.payload(info.file, entry)?;
            let known = validated.contains(&(info.file, entry.record));
            let what = || {
                format!(
                    "{}: segment {} generation {}",
                    at(entry.record as usize),
                    entry.segment,
                    entry.generation
                )
            };
            let id = entry.segment;
            if is_structure_segment_id(id) {
                structure = Some(if known {
                    // SAFETY: these bytes (this record of this immutable map) passed
                    // `validate_structure` in an earlier join: the id at a record never
                    // changes, so neither does the validation that applies.
                    unsafe { structure_unchecked(bytes) }
                } else {
                    validate_structure(bytes, &what())?
                });
            } else if is_tree_chunk_segment_id(id) {
                trees.push(if known {
                    // SAFETY: as above, with `validate_tree_chunk`.
                    unsafe { tree_chunk_unchecked(bytes) }
                } else {
                    validate_tree_chunk(bytes, &what())?
                });
            } else if is_chunk_segment_id(id) {
                chunks.push(if known {
                    // SAFETY: as above, with `validate_chunk`.
                    unsafe { chunk_unchecked(bytes) }
                } else {
                    validate_chunk(bytes, &what())?
                });
            } else {
                parts.push(if known {
                    // SAFETY: as above, with `validate_layer`.
                    unsafe { layer_unchecked(bytes) }
                } else {
                    validate_layer(bytes, &what())?
                });
            }
            validated.insert((info.file, entry.record));
        }
        drop(validated);
        let inconsistent = |reason: String| {
            RecordingError::Snapshot(SnapshotError::Inconsistent {
                what: format!("{} cut {}", at(info.payload - RECORD_HEADER_LEN), cut),
                reason,
            })
        };
        let structure =
            structure.ok_or_else(|| inconsistent("the cut names no structure segment".into()))?;
        ArchivedScene::new(manifest, structure, parts, chunks, trees).map_err(inconsistent)
    }
}

/// Scans the records of `file` (number `index` in the recording), appending its complete
/// cuts to `cuts` and any damage to `defects`.
fn scan(file: &mut MappedFile, index: usize, cuts: &mut Vec<CutInfo>, defects: &mut Vec<String>) {
    let map: &[u8] = &file.map;
    let mut at = FIRST_RECORD_AT;
    let mut first_cut_of_file = None;
    let mut since_last_cut = (0u32, 0u64);
    // The segment ids the last cut of the file names.
    let mut named = std::collections::BTreeSet::new();
    while at < map.len() {
        let (header, payload) = match RecordHeader::decode(map, at) {
            Ok(record) => record,
            Err(RecordDefect::Truncated) => break,
            Err(RecordDefect::Corrupt(reason)) => {
                defects.push(format!(
                    "{} at byte {at}: {reason}; the file is read up to there",
                    file.path.display()
                ));
                break;
            }
        };
        let next = next_record_at(payload.end);
        match header.kind {
            RecordKind::Segment => {
                let [id, generation, ..] = header.words;
                file.segments.insert(
                    at as u64,
                    SegmentRecord {
                        id,
                        generation,
                        payload: payload.clone(),
                    },
                );
                since_last_cut.0 += 1;
                since_last_cut.1 += (next - at) as u64;
            }
            RecordKind::Cut => {
                let [
                    generation,
                    session,
                    writer_unix_ns,
                    recorder_unix_ns,
                    manifest_len,
                ] = header.words;
                let checked = check_cut(file, map, at, &payload, manifest_len);
                let (list, list_range) = match checked {
                    Ok(list) => list,
                    Err(reason) => {
                        defects.push(format!(
                            "{} at byte {at}: cut {generation}: {reason}; the file is read \
                             up to there",
                            file.path.display()
                        ));
                        break;
                    }
                };
                let checkpoint = if list.checkpoint {
                    cuts.len()
                } else if let Some(last) = first_cut_of_file.and(cuts.last()) {
                    last.checkpoint
                } else {
                    defects.push(format!(
                        "{} at byte {at}: the file's first cut lists changes, not every \
                         segment; the file is not readable",
                        file.path.display()
                    ));
                    break;
                };
                first_cut_of_file.get_or_insert(cuts.len());
                if list.checkpoint {
                    named.clear();
                }
                for id in &list.removed {
                    named.remove(id);
                }
                named.extend(list.set.iter().map(|e| e.segment));
                let segments = named.len();
                cuts.push(CutInfo {
                    summary: CutSummary {
                        generation,
                        session,
                        writer_unix_ns,
                        recorder_unix_ns,
                        segments_added: since_last_cut.0,
                        segments: segments as u32,
                        bytes_added: since_last_cut.1 + (next - at) as u64,
                    },
                    file: index,
                    payload: payload.start,
                    manifest_len: manifest_len as usize,
                    list: list_range,
                    checkpoint,
                });
                since_last_cut = (0, 0);
            }
        }
        at = next;
    }
}

/// Checks a cut record's manifest length and entry list: every entry names a segment
/// record before it in the file with the entry's id and generation.
fn check_cut(
    file: &MappedFile,
    map: &[u8],
    at: usize,
    payload: &std::ops::Range<usize>,
    manifest_len: u64,
) -> Result<(CutList, std::ops::Range<usize>), String> {
    let manifest_len = usize::try_from(manifest_len)
        .ok()
        .filter(|&m| m <= payload.len())
        .ok_or_else(|| format!("manifest length {manifest_len} exceeds the record"))?;
    let list_start = payload.start + cut_list_at(manifest_len);
    if list_start > payload.end {
        return Err("no room for the entry list".into());
    }
    let list = CutList::decode(&map[list_start..payload.end])?;
    for e in &list.set {
        let matches = e.record < at as u64
            && file
                .segments
                .get(&e.record)
                .is_some_and(|s| s.id == e.segment && s.generation == e.generation);
        if !matches {
            return Err(format!(
                "entry for segment {} generation {} names byte {}, not that segment's record",
                e.segment, e.generation, e.record
            ));
        }
    }
    Ok((list, list_start..payload.end))
}
