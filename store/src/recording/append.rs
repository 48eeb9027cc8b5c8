//! [`RecordingWriter`]: appends cuts to a recording, each segment once per file.

use super::error::RecordingError;
use super::files::{RecordingFileName, list_files, unix_ns};
use super::format::{
    CutEntry, CutList, FIRST_RECORD_AT, RECORD_HEADER_LEN, RecordHeader, RecordKind, cut_list_at,
    file_header, next_record_at,
};
use crate::snapshot::FORMAT_VERSION;
use std::collections::VecDeque;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Cuts between two checkpoints (cut records that list every segment): opening a cut
/// applies at most this many lists of changes to its checkpoint's.
const CUTS_PER_CHECKPOINT: u32 = 256;

/// Bounds of a recording. Files are the unit dropped: the oldest whole file goes when a
/// bound is passed, and nothing else is rewritten.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordingOptions {
    /// Largest size of one file before the next cut starts a new one (default 256 MiB:
    /// each file re-records the whole scene once, about 4% of a file for the office).
    pub file_bytes: u64,
    /// Keep the files' total under this many bytes by dropping the oldest (none by
    /// default). Files then hold at most a quarter of it each.
    pub max_bytes: Option<u64>,
    /// Drop files whose newest cut is older than this (none by default). Files then span
    /// at most a quarter of it each.
    pub max_age: Option<Duration>,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        RecordingOptions {
            file_bytes: 256 << 20,
            max_bytes: None,
            max_age: None,
        }
    }
}

/// One segment of a cut to record: its id, generation and validated archived bytes.
#[derive(Debug, Clone, Copy)]
pub struct RecordedSegment<'a> {
    /// The segment id (a layer part, a point or tree chunk, the structure).
    pub id: u64,
    /// Its generation.
    pub generation: u64,
    /// Its archived bytes.
    pub bytes: &'a [u8],
}

/// A cut to record, as a reader received it.
#[derive(Debug, Clone)]
pub struct CutToRecord<'a> {
    /// The cut's generation.
    pub generation: u64,
    /// The writer session that published it.
    pub session: u64,
    /// When the writer began publishing it (ns since the Unix epoch, writer's clock).
    pub writer_unix_ns: u64,
    /// The store's manifest bytes.
    pub manifest: &'a [u8],
    /// Every segment the cut names, ascending by id.
    pub segments: Vec<RecordedSegment<'a>>,
}

/// What one [`RecordingWriter::append_cut`] wrote.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AppendReport {
    /// Segments appended (those not already in the current file).
    pub segments_written: usize,
    /// Bytes added to the recording, record headers and padding included.
    pub bytes_written: u64,
    /// Whether this cut started a new file.
    pub new_file: bool,
    /// Files dropped by the bounds after this cut.
    pub files_dropped: usize,
}

/// A file being appended to.
struct OpenFile {
    path: PathBuf,
    file: File,
    /// Where the next record starts (after the last complete cut).
    end: u64,
    /// When the file was created (recorder clock).
    created_unix_ns: u64,
    /// When its last cut was appended (recorder clock).
    last_cut_unix_ns: u64,
    /// The last cut's segments in this file: `(session, entry)` ascending by segment id.
    last_cut: Vec<(u64, CutEntry)>,
    /// Cuts since the last checkpoint of this file (`None` before the first cut).
    since_checkpoint: Option<u32>,
}

/// A closed file of the recording, kept until a bound drops it.
struct ClosedFile {
    path: PathBuf,
    bytes: u64,
    last_cut_unix_ns: u64,
}

/// Appends cuts to a recording: a folder of numbered files, each self-contained (its
/// first cut's segments are all in it), so that dropping the oldest file rewrites
/// nothing. Every record carries a CRC and the cut record is written last: a recorder
/// stopped at any point leaves every complete cut readable. See `docs/DESIGN.md` §11.
pub struct RecordingWriter {
    dir: PathBuf,
    options: RecordingOptions,
    current: Option<OpenFile>,
    closed: VecDeque<ClosedFile>,
    next_number: u64,
}

impl RecordingWriter {
    /// Opens `dir` for recording, creating it if needed. A folder that already holds a
    /// recording is continued in a new file (older files are kept as they are).
    ///
    /// # Errors
    /// [`RecordingError::Io`] when the folder cannot be created or listed;
    /// [`RecordingError::Format`] when it holds files that are not a recording's.
    pub fn create(
        dir: impl AsRef<Path>,
        options: RecordingOptions,
    ) -> Result<Self, RecordingError> {
        let dir = dir.as_ref().to_path_buf();
        std::fs::create_dir_all(&dir).map_err(|source| RecordingError::Io {
            path: dir.display().to_string(),
            source,
        })?;
        let existing = list_files(&dir)?;
        let next_number = existing.last().map_or(1, |f| f.number + 1);
        let closed = existing
            .into_iter()
            .map(|f| {
                let meta = std::fs::metadata(&f.path).map_err(|source| RecordingError::Io {
                    path: f.path.display().to_string(),
                    source,
                })?;
                let modified = meta
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos() as u64);
                Ok(ClosedFile {
                    path: f.path,
                    bytes: meta.len(),
                    last_cut_unix_ns: modified,
                })
            })
            .collect::<Result<_, RecordingError>>()?;
        Ok(RecordingWriter {
            dir,
            options,
            current: None,
            closed,
            next_number,
        })
    }

    /// The recording's folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Appends `cut`: each of its segments not already in the current file, then the cut
    /// record naming them. Starts a new file first when the current one is full or old.
    ///
    /// # Errors
    /// [`RecordingError::Io`] naming the file (a full disk: "No space left on device");
    /// the partial records of this cut are cut off again, so the recording stays readable
    /// up to the previous cut, and a later call may try again.
    pub fn append_cut(&mut self, cut: &CutToRecord<'_>) -> Result<AppendReport, RecordingError> {
        if cut.segments.windows(2).any(|w| w[0].id >= w[1].id) {
            return Err(RecordingError::Format {
                path: self.dir.display().to_string(),
                reason: format!(
                    "cut {} lists its segments out of order; refused before writing",
                    cut.generation
                ),
            });
        }
        let mut report = AppendReport::default();
        let now = unix_ns();
        if self.current.as_ref().is_some_and(|f| self.is_full(f, now)) {
            self.close_current()?;
        }
        if self.current.is_none() {
            self.current = Some(self.new_file(now)?);
            report.new_file = true;
        }
        let file = self.current.as_mut().expect("opened above");
        let start = file.end;
        match append_to(file, cut, now, &mut report) {
            Ok(()) => {}
            Err(e) => {
                // Cut off what this cut wrote: the file ends after its last complete cut.
                let _ = file.file.set_len(start);
                file.end = start;
                return Err(e);
            }
        }
        report.bytes_written = file.end - start;
        file.last_cut_unix_ns = now;
        report.files_dropped = self.enforce_bounds(now)?;
        Ok(report)
    }

    /// Syncs the current file to disk. Called on drop too (errors then ignored).
    ///
    /// # Errors
    /// [`RecordingError::Io`] naming the file.
    pub fn sync(&self) -> Result<(), RecordingError> {
        if let Some(f) = &self.current {
            f.file.sync_data().map_err(|source| io(&f.path, source))?;
        }
        Ok(())
    }

    /// Whether `file` has reached its size or age bound.
    fn is_full(&self, file: &OpenFile, now: u64) -> bool {
        let quarter = |b: u64| (b / 4).max(1 << 20);
        let bytes = self.options.max_bytes.map_or(self.options.file_bytes, |m| {
            quarter(m).min(self.options.file_bytes)
        });
        let age = self
            .options
            .max_age
            .is_some_and(|a| now.saturating_sub(file.created_unix_ns) > a.as_nanos() as u64 / 4);
        file.end >= bytes || age
    }

    fn new_file(&mut self, now: u64) -> Result<OpenFile, RecordingError> {
        let path = self
            .dir
            .join(RecordingFileName(self.next_number).to_string());
        let file = File::options()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|source| io(&path, source))?;
        let header = file_header(self.next_number, now, FORMAT_VERSION);
        if let Err(source) = file.write_all_at(&header, 0) {
            drop(file);
            let _ = std::fs::remove_file(&path);
            return Err(io(&path, source));
        }
        // The folder entry survives a crash once the folder is synced.
        if let Ok(d) = File::open(&self.dir) {
            let _ = d.sync_all();
        }
        self.next_number += 1;
        Ok(OpenFile {
            path,
            file,
            end: FIRST_RECORD_AT as u64,
            created_unix_ns: now,
            last_cut_unix_ns: now,
            last_cut: Vec::new(),
            since_checkpoint: None,
        })
    }

    fn close_current(&mut self) -> Result<(), RecordingError> {
        if let Some(f) = self.current.take() {
            f.file.sync_data().map_err(|source| io(&f.path, source))?;
            self.closed.push_back(ClosedFile {
                path: f.path,
                bytes: f.end,
                last_cut_unix_ns: f.last_cut_unix_ns,
            });
        }
        Ok(())
    }

    /// Drops the oldest closed files while a bound is passed; the current file stays.
    fn enforce_bounds(&mut self, now: u64) -> Result<usize, RecordingError> {
        let current = self.current.as_ref().map_or(0, |f| f.end);
        let mut total: u64 = current + self.closed.iter().map(|f| f.bytes).sum::<u64>();
        let mut dropped = 0;
        while let Some(oldest) = self.closed.front() {
            let too_big = self.options.max_bytes.is_some_and(|m| total > m);
            let too_old = self
                .options
                .max_age
                .is_some_and(|a| now.saturating_sub(oldest.last_cut_unix_ns) > a.as_nanos() as u64);
            if !too_big && !too_old {
                break;
            }
            std::fs::remove_file(&oldest.path).map_err(|source| io(&oldest.path, source))?;
            total -= oldest.bytes;
            self.closed.pop_front();
            dropped += 1;
        }
        Ok(dropped)
    }
}

impl Drop for RecordingWriter {
    fn drop(&mut self) {
        let _ = self.sync();
    }
}

/// Appends `cut`'s new segments and its cut record to `file`, updating `file` only as
/// far as the records written.
fn append_to(
    file: &mut OpenFile,
    cut: &CutToRecord<'_>,
    now: u64,
    report: &mut AppendReport,
) -> Result<(), RecordingError> {
    let last_cut = std::mem::take(&mut file.last_cut);
    let written = append_records(file, &last_cut, cut, now, report);
    file.last_cut = match written {
        Ok((entries, checkpoint, since)) => {
            file.since_checkpoint = Some(if checkpoint { 0 } else { since });
            entries.into_iter().map(|e| (cut.session, e)).collect()
        }
        Err(e) => {
            file.last_cut = last_cut;
            return Err(e);
        }
    };
    Ok(())
}

/// The records of [`append_to`]; gives the cut's entries, whether its list is a
/// checkpoint, and the cuts since the file's last checkpoint.
fn append_records(
    file: &mut OpenFile,
    last_cut: &[(u64, CutEntry)],
    cut: &CutToRecord<'_>,
    now: u64,
    report: &mut AppendReport,
) -> Result<(Vec<CutEntry>, bool, u32), RecordingError> {
    let mut entries = Vec::with_capacity(cut.segments.len());
    let mut last = last_cut.iter().peekable();
    for s in &cut.segments {
        while last.next_if(|(_, e)| e.segment < s.id).is_some() {}
        let recorded = last
            .peek()
            .filter(|(session, e)| {
                e.segment == s.id && *session == cut.session && e.generation == s.generation
            })
            .map(|(_, e)| e.record);
        let record = match recorded {
            Some(at) => at,
            None => {
                let header = RecordHeader {
                    kind: RecordKind::Segment,
                    len: s.bytes.len() as u64,
                    words: [s.id, s.generation, cut.session, 0, 0],
                };
                report.segments_written += 1;
                write_record(file, &header, &[s.bytes])?
            }
        };
        entries.push(CutEntry {
            segment: s.id,
            generation: s.generation,
            record,
        });
    }
    let since = file.since_checkpoint.map_or(CUTS_PER_CHECKPOINT, |n| n + 1);
    let list = if since >= CUTS_PER_CHECKPOINT {
        CutList {
            checkpoint: true,
            set: entries.clone(),
            removed: Vec::new(),
        }
    } else {
        changes_since(last_cut, &entries)
    };
    let mut tail = vec![0u8; cut_list_at(cut.manifest.len()) - cut.manifest.len()];
    list.encode(&mut tail);
    let header = RecordHeader {
        kind: RecordKind::Cut,
        len: (cut.manifest.len() + tail.len()) as u64,
        words: [
            cut.generation,
            cut.session,
            cut.writer_unix_ns,
            now,
            cut.manifest.len() as u64,
        ],
    };
    write_record(file, &header, &[cut.manifest, &tail])?;
    Ok((entries, list.checkpoint, since))
}

/// The entries of `now` that differ from `last`'s, and the ids `last` had that `now`
/// lacks (both ascending by id).
fn changes_since(last: &[(u64, CutEntry)], now: &[CutEntry]) -> CutList {
    let mut list = CutList::default();
    let mut last = last.iter().map(|(_, e)| e).peekable();
    for e in now {
        while let Some(gone) = last.next_if(|l| l.segment < e.segment) {
            list.removed.push(gone.segment);
        }
        if last.next_if(|l| l.segment == e.segment) != Some(e) {
            list.set.push(*e);
        }
    }
    list.removed.extend(last.map(|l| l.segment));
    list
}

/// Writes one record (header, then `payload` pieces back to back) at the file's end and
/// returns its offset; the end moves past it.
fn write_record(
    file: &mut OpenFile,
    header: &RecordHeader,
    payload: &[&[u8]],
) -> Result<u64, RecordingError> {
    let at = file.end;
    let mut bytes = Vec::with_capacity(RECORD_HEADER_LEN + header.len as usize);
    bytes.extend_from_slice(&[0; RECORD_HEADER_LEN]);
    for p in payload {
        bytes.extend_from_slice(p);
    }
    let encoded = header.encode(&bytes[RECORD_HEADER_LEN..]);
    bytes[..RECORD_HEADER_LEN].copy_from_slice(&encoded);
    file.file
        .write_all_at(&bytes, at)
        .map_err(|source| io(&file.path, source))?;
    file.end = next_record_at(at as usize + bytes.len()) as u64;
    Ok(at)
}

fn io(path: &Path, source: std::io::Error) -> RecordingError {
    RecordingError::Io {
        path: path.display().to_string(),
        source,
    }
}
