//! `.ygg` snapshot files: the manifest and layer segments back to back at 128-aligned
//! offsets behind a segment table; [`SnapshotFile`] maps one and validates it once.

#![allow(
    unsafe_code,
    reason = "memory-mapping a file and re-deriving references to bytes validated at open"
)]

use super::cut::ArchivedScene;
use super::validate::{validate_layer, validate_manifest, validate_structure};
use crate::bytes::{ARCHIVE_ALIGN, SegmentBytes};
use crate::snapshot::schema::{
    ArchivedLayerSegment, ArchivedManifest, ArchivedStructure, FORMAT_VERSION,
};
use crate::{SceneGraph, SnapshotError};
use std::path::Path;

/// First eight bytes of every `.ygg` file.
pub const FILE_MAGIC: &[u8; 8] = b"YGGSNAP\0";

fn align_up(n: usize) -> usize {
    n.div_ceil(ARCHIVE_ALIGN) * ARCHIVE_ALIGN
}

/// Lays segments out as a `.ygg` file: magic, version, count, `(offset, len)` table,
/// then each segment at a 128-aligned offset. The first segment is the manifest, the
/// second the structure, then one segment per layer.
fn pack_file(segments: &[&[u8]]) -> Vec<u8> {
    let header = 16 + 16 * segments.len();
    let mut out = Vec::with_capacity(
        align_up(header) + segments.iter().map(|s| align_up(s.len())).sum::<usize>(),
    );
    out.extend_from_slice(FILE_MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(segments.len() as u32).to_le_bytes());
    let mut offset = align_up(header);
    for s in segments {
        out.extend_from_slice(&(offset as u64).to_le_bytes());
        out.extend_from_slice(&(s.len() as u64).to_le_bytes());
        offset = align_up(offset + s.len());
    }
    for s in segments {
        out.resize(align_up(out.len()), 0);
        out.extend_from_slice(s);
    }
    out
}

/// Reads the segment table of a `.ygg` file; every range is checked against `bytes`.
fn unpack_file(bytes: &[u8], what: &str) -> Result<Vec<std::ops::Range<usize>>, SnapshotError> {
    let layout = |reason: String| SnapshotError::Layout {
        what: what.to_owned(),
        reason,
    };
    if bytes.len() < 16 || &bytes[..8] != FILE_MAGIC {
        return Err(SnapshotError::BadMagic(what.to_owned()));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let version = word(8);
    if version != FORMAT_VERSION {
        return Err(SnapshotError::SchemaVersion {
            what: what.to_owned(),
            found: version,
            expected: FORMAT_VERSION,
        });
    }
    let count = word(12) as usize;
    let table_end = count
        .checked_mul(16)
        .and_then(|t| t.checked_add(16))
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            layout(format!(
                "segment table of {count} entries runs past the end of the file"
            ))
        })?;
    if count == 0 {
        return Err(layout("no manifest segment".into()));
    }
    let mut ranges = Vec::with_capacity(count);
    for i in 0..count {
        let at = 16 + 16 * i;
        let off = u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        let len = u64::from_le_bytes(bytes[at + 8..at + 16].try_into().expect("8 bytes"));
        let end = off.checked_add(len).filter(|&e| e <= bytes.len() as u64);
        let (Some(end), true) = (end, off as usize >= table_end) else {
            return Err(layout(format!(
                "segment {i} ({off}+{len}) lies outside the file"
            )));
        };
        if !(off as usize).is_multiple_of(ARCHIVE_ALIGN) {
            return Err(layout(format!(
                "segment {i} at offset {off} is not {ARCHIVE_ALIGN}-byte aligned"
            )));
        }
        ranges.push(off as usize..end as usize);
    }
    Ok(ranges)
}

/// A `.ygg` snapshot file, memory-mapped and validated once at [`SnapshotFile::open`].
///
/// ```
/// # use ygg_store::{SceneGraph, SnapshotFile, SceneView, NodeId};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let rooms = g.add_layer("rooms")?;
/// g.add_node(NodeId(1), rooms)?;
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("scene.ygg");
/// g.save(&path)?;
/// let file = SnapshotFile::open(&path)?;
/// assert_eq!(file.view().node_count(), 1);
/// # Ok(()) }
/// ```
pub struct SnapshotFile {
    bytes: Backing,
    manifest: std::ops::Range<usize>,
    structure: std::ops::Range<usize>,
    layers: Vec<std::ops::Range<usize>>,
}

enum Backing {
    Mapped(memmap2::Mmap),
    Owned(SegmentBytes),
}

impl Backing {
    fn as_slice(&self) -> &[u8] {
        match self {
            Backing::Mapped(m) => m,
            Backing::Owned(v) => v,
        }
    }
}

impl SnapshotFile {
    /// Memory-maps a `.ygg` file and validates every segment.
    ///
    /// # Errors
    /// I/O errors, a foreign or truncated file, or bytes that fail validation.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, SnapshotError> {
        let path = path.as_ref();
        let what = path.display().to_string();
        let io = |source| SnapshotError::Io {
            path: what.clone(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if len == 0 {
            return Err(SnapshotError::BadMagic(what));
        }
        // SAFETY: the map is read-only and private to this process. Snapshot files are
        // written once and never modified in place: `save` writes a new file and renames
        // it over the old one, so this mapping keeps the old inode's bytes. A process that
        // truncates or rewrites the file in place is outside this contract (as for any
        // mmap-based reader) and documented on `SnapshotFile`.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        Self::from_backing(Backing::Mapped(map), &what)
    }

    /// Validates snapshot-file bytes held in memory (copied into aligned storage).
    ///
    /// # Errors
    /// As [`SnapshotFile::open`].
    pub fn from_bytes(bytes: &[u8], what: &str) -> Result<Self, SnapshotError> {
        let mut v = SegmentBytes::with_capacity(bytes.len());
        v.extend_from_slice(bytes);
        Self::from_backing(Backing::Owned(v), what)
    }

    fn from_backing(bytes: Backing, what: &str) -> Result<Self, SnapshotError> {
        let data = bytes.as_slice();
        let mut ranges = unpack_file(data, what)?;
        if ranges.len() < 2 {
            return Err(SnapshotError::Layout {
                what: what.to_owned(),
                reason: "no structure segment after the manifest".into(),
            });
        }
        let manifest_range = ranges.remove(0);
        let structure_range = ranges.remove(0);
        let manifest = validate_manifest(&data[manifest_range.clone()], what)?;
        let structure = validate_structure(
            &data[structure_range.clone()],
            &format!("{what}: structure"),
        )?;
        let mut layers = Vec::with_capacity(ranges.len());
        for (i, r) in ranges.iter().enumerate() {
            layers.push(validate_layer(
                &data[r.clone()],
                &format!("{what}: layer segment {i}"),
            )?);
        }
        // Files keep every layer's points inline: a file holds no chunk segments.
        ArchivedScene::new(manifest, structure, layers, Vec::new(), Vec::new()).map_err(
            |reason| SnapshotError::Inconsistent {
                what: what.to_owned(),
                reason,
            },
        )?;
        Ok(SnapshotFile {
            bytes,
            manifest: manifest_range,
            structure: structure_range,
            layers: ranges,
        })
    }

    /// The scene, queried in place.
    pub fn view(&self) -> ArchivedScene<'_> {
        let data = self.bytes.as_slice();
        // SAFETY: `from_backing` validated these exact ranges of these exact bytes with
        // `validate_manifest` / `validate_layer` (bytecheck + `check_layer`), and the
        // backing bytes are immutable for the life of `self`.
        let manifest =
            unsafe { rkyv::access_unchecked::<ArchivedManifest>(&data[self.manifest.clone()]) };
        // SAFETY: as above, this range was validated as an `ArchivedStructure`.
        let structure =
            unsafe { rkyv::access_unchecked::<ArchivedStructure>(&data[self.structure.clone()]) };
        let layers = self
            .layers
            .iter()
            // SAFETY: as above, each range was validated as an `ArchivedLayerSegment`.
            .map(|r| unsafe { rkyv::access_unchecked::<ArchivedLayerSegment>(&data[r.clone()]) })
            .collect();
        // `from_backing` ran `ArchivedScene::new` on this cut.
        ArchivedScene::new_prechecked(manifest, structure, layers, Vec::new(), Vec::new())
    }

    /// Size of the file in bytes.
    pub fn len(&self) -> usize {
        self.bytes.as_slice().len()
    }

    /// Whether the file is empty (never true for an opened snapshot).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes of each segment: the manifest's and the structure's together, then every
    /// layer segment's in manifest order (ascending layer id, as
    /// [`crate::SceneView::layers`] lists them).
    pub fn segment_sizes(&self) -> (usize, Vec<usize>) {
        (
            self.manifest.len() + self.structure.len(),
            self.layers.iter().map(|r| r.len()).collect(),
        )
    }
}

impl SceneGraph {
    /// Archives the graph into an in-memory, validated snapshot (the bytes a `.ygg` file
    /// would hold). Handy for tests and examples.
    pub fn to_snapshot(&self) -> SnapshotFile {
        SnapshotFile::from_bytes(&self.to_file_bytes(), "in-memory snapshot")
            .expect("a freshly archived graph validates")
    }

    /// Writes the graph to a `.ygg` snapshot file, crash-safely: the bytes go to a new
    /// temporary file in the same folder, which is synced, renamed over `path` and the
    /// folder synced. A reader that maps the old file keeps its (unchanged) bytes; a
    /// crash, a full disk or any other failure leaves the old file as it was and removes
    /// the temporary one.
    ///
    /// # Errors
    /// [`SnapshotError::Io`] naming `path` when the file cannot be written (a full disk
    /// says "No space left on device"); the previous file is intact.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), SnapshotError> {
        let path = path.as_ref();
        replace_file(path, &self.to_file_bytes()).map_err(|source| SnapshotError::Io {
            path: path.display().to_string(),
            source,
        })
    }

    /// The bytes of the graph's `.ygg` file.
    fn to_file_bytes(&self) -> Vec<u8> {
        let archived = self.to_segments();
        let mut segments: Vec<&[u8]> = vec![&archived.manifest, &archived.structure];
        segments.extend(archived.layers.iter().map(|l| l.as_slice()));
        pack_file(&segments)
    }
}

/// Replaces the file at `path` with `bytes` atomically: a temporary file in the same
/// folder (so that the rename stays within one file system), written and synced, renamed
/// over `path`, then the folder synced so that the rename survives a crash.
fn replace_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name().map_or_else(
        || std::ffi::OsString::from("snapshot"),
        std::ffi::OsStr::to_os_string,
    );
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    let mut tmp = tempfile::Builder::new()
        .prefix(&prefix)
        .suffix(".tmp")
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    std::fs::File::open(dir)?.sync_all()
}
