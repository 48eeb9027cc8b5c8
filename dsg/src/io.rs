//! Reading Spark-DSG files from disk: JSON or binary, plain or gzip-compressed.

use std::ffi::OsStr;
use std::fs::File;
use std::io::Read;
use std::path::Path;

use flate2::read::MultiGzDecoder;

use super::binary::{is_binary, parse_binary_impl};
use super::error::DsgImportError;
use super::json::parse_json_impl;
use super::model::DsgGraph;
use super::progress::{ImportPhase, ImportProgress};
use super::report::{ImportOptions, Imported};

const CHUNK: usize = 4 << 20;

/// Reads a Spark-DSG file: JSON (`.json`) or binary (`.sparkdsg`), plain or
/// gzip-compressed (`.json.gz`).
///
/// The format is detected from the content, not from the extension: gzip by its
/// magic bytes; then a file starting with the binary header (`dd 09000000
/// "SPARK_DSG"`) is binary, and one starting with `{` (after whitespace) is JSON.
/// Otherwise the extension decides as in Spark-DSG's `file_io.cpp`: `.sparkdsg` and
/// no extension mean binary (such a file without header is then rejected as legacy
/// binary), anything else JSON. The file name is used in errors and stored as
/// [`DsgGraph::source`].
///
/// # Errors
/// [`DsgImportError::Io`] if the file cannot be read, [`DsgImportError::Gzip`] for
/// corrupt compressed data, and every error of [`parse_json`](super::parse_json) or
/// [`parse_binary`](super::parse_binary).
pub fn read_file(path: impl AsRef<Path>) -> Result<DsgGraph, DsgImportError> {
    read_file_with_progress(path, &mut |_| {})
}

/// [`read_file`] that reports [`ImportPhase::Read`], [`ImportPhase::Decompress`]
/// (gzip only), [`ImportPhase::Parse`] (JSON parse or binary decode),
/// [`ImportPhase::Validate`] and
/// [`ImportPhase::Done`] to `progress`.
///
/// # Errors
/// As [`read_file`].
pub fn read_file_with_progress(
    path: impl AsRef<Path>,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<DsgGraph, DsgImportError> {
    import_file(path, ImportOptions::STRICT, progress).map(|i| i.graph)
}

/// [`read_file`] with [`ImportOptions`]: a lenient import drops what cannot be imported
/// (edges to absent nodes, duplicate edges, nodes of undeclared layers or unknown
/// types, ...: every [`DropClass`](crate::DropClass)) and lists it in
/// [`Imported::report`], for JSON and binary files alike.
///
/// # Errors
/// As [`read_file`], less the faults a lenient import drops.
pub fn read_file_with(
    path: impl AsRef<Path>,
    options: ImportOptions,
) -> Result<Imported, DsgImportError> {
    import_file(path, options, &mut |_| {})
}

/// The general file import: [`read_file_with`] that reports its phases to `progress`
/// as [`read_file_with_progress`] does.
///
/// # Errors
/// As [`read_file_with`].
pub fn import_file(
    path: impl AsRef<Path>,
    options: ImportOptions,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Imported, DsgImportError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let bytes = read_bytes(path, &name, progress)?;
    if binary_content(&bytes, path) {
        parse_binary_impl(&bytes, &name, options, progress)
    } else {
        parse_json_impl(&bytes, &name, options, progress)
    }
}

/// Whether `bytes` (decompressed) of the file at `path` are to be read as binary.
fn binary_content(bytes: &[u8], path: &Path) -> bool {
    if is_binary(bytes) {
        return true;
    }
    if bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{') {
        return false;
    }
    let mut ext = path.extension();
    if ext == Some(OsStr::new("gz")) {
        ext = path.file_stem().map(Path::new).and_then(Path::extension);
    }
    ext.is_none_or(|e| e == "sparkdsg")
}

/// Reads a file and gunzips it when it starts with the gzip magic bytes.
pub(crate) fn read_bytes(
    path: &Path,
    name: &str,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Vec<u8>, DsgImportError> {
    let io_err = |source| DsgImportError::Io {
        file: name.to_owned(),
        source,
    };
    let mut file = File::open(path).map_err(io_err)?;
    let total = file.metadata().map_err(io_err)?.len();
    let mut raw = Vec::with_capacity(usize::try_from(total).unwrap_or(0).saturating_add(1));
    progress(ImportProgress::new(ImportPhase::Read, 0, Some(total)));
    read_chunked(&mut file, &mut raw, |n| {
        progress(ImportProgress::new(ImportPhase::Read, n, Some(total)));
    })
    .map_err(io_err)?;
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Ok(raw);
    }
    // The gzip trailer's last 4 bytes hold the uncompressed size modulo 2^32.
    let hint = raw
        .len()
        .checked_sub(4)
        .and_then(|at| raw.get(at..))
        .and_then(|t| <[u8; 4]>::try_from(t).ok())
        .map(|t| u64::from(u32::from_le_bytes(t)));
    let capacity = hint
        .and_then(|h| usize::try_from(h).ok())
        .unwrap_or(0)
        .min(raw.len().saturating_mul(64));
    let mut out = Vec::with_capacity(capacity);
    progress(ImportProgress::new(ImportPhase::Decompress, 0, hint));
    read_chunked(&mut MultiGzDecoder::new(&raw[..]), &mut out, |n| {
        progress(ImportProgress::new(ImportPhase::Decompress, n, hint));
    })
    .map_err(|source| DsgImportError::Gzip {
        file: name.to_owned(),
        source,
    })?;
    Ok(out)
}

fn read_chunked(
    r: &mut impl Read,
    out: &mut Vec<u8>,
    mut report: impl FnMut(u64),
) -> std::io::Result<()> {
    loop {
        let n = r.by_ref().take(CHUNK as u64).read_to_end(out)?;
        report(out.len() as u64);
        if n == 0 {
            return Ok(());
        }
    }
}
