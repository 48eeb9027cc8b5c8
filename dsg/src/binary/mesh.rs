//! The binary `Mesh` (`src/serialization/mesh_serialization.cpp`): four flag bools
//! (colors, timestamps, labels, first-seen stamps), then points (`ARR32` of three
//! FLOAT32), colors (`ARR32` of four UINT8), stamps (UINT64), labels (UINT32),
//! first-seen stamps (UINT64) and faces (`ARR32` of `ARR32(3)` UINT64). Every vector
//! is written whatever the flags say; spark_dsg 1.1.3 reads it without version
//! branches.
//!
//! Reading keeps points, faces and labels (what [`DsgMesh`] holds) and checks the
//! rest; a face index must fit u32, as in the JSON importer.

use super::reader::{Cursor, DecodeError, Decoded, Scalar, Tag, f32_at, u32_at, u64_as_u32_at};
use super::writer::Writer;
use crate::model::DsgMesh;
use crate::raw::{Num, RawMesh};

/// Encoded size of one point (three tagged FLOAT32).
const POINT: usize = 3 * 5;
/// Encoded size of one face (`ARR32(3)` header and three tagged UINT64).
const FACE: usize = 5 + 3 * 9;

/// Reads a mesh into the JSON importer's raw form.
pub(super) fn read(c: &mut Cursor<'_>) -> Decoded<RawMesh> {
    for flag in [
        "has_colors",
        "has_timestamps",
        "has_labels",
        "has_first_seen_stamps",
    ] {
        c.bool(flag)?;
    }
    let n = c.array_len(POINT, "points")?;
    let mut points = Vec::with_capacity(n);
    let fast = c.records(n, &mut points, |r: &[u8; POINT]| {
        Some([f32_at(r, 0)?, f32_at(r, 5)?, f32_at(r, 10)?].map(|x| Num(f64::from(x))))
    });
    if !fast {
        for i in 0..n {
            let p = c
                .vec3_f32("")
                .map_err(|e| e.within(format!("points[{i}]")))?;
            points.push(p.map(|x| Num(f64::from(x))));
        }
    }
    let n = c.array_len(4 * Scalar::U8.encoded(), "colors")?;
    let u = Tag::U8 as u8;
    let fast = c.records(n, &mut Vec::new(), |r: &[u8; 8]| {
        (r[0] == u && r[2] == u && r[4] == u && r[6] == u).then_some(())
    });
    if !fast {
        for i in 0..n {
            for _ in 0..4 {
                c.u8("").map_err(|e| e.within(format!("colors[{i}]")))?;
            }
        }
    }
    skip_u64s(c, "stamps")?;
    let n = c.array_len(Scalar::U32.encoded(), "labels")?;
    let mut labels = Vec::with_capacity(n);
    if !c.records(n, &mut labels, |r: &[u8; 5]| u32_at(r, 0)) {
        for i in 0..n {
            labels.push(c.u32("").map_err(|e| e.within(format!("labels[{i}]")))?);
        }
    }
    skip_u64s(c, "first_seen_stamps")?;
    let n = c.array_len(FACE, "faces")?;
    let mut faces = Vec::with_capacity(n);
    let fast = c.records(n, &mut faces, |r: &[u8; FACE]| {
        let header = r[..5] == [Tag::Arr32 as u8, 3, 0, 0, 0];
        let f = [
            u64_as_u32_at(r, 5)?,
            u64_as_u32_at(r, 14)?,
            u64_as_u32_at(r, 23)?,
        ];
        header.then_some(f)
    });
    if !fast {
        for i in 0..n {
            faces.push(face(c).map_err(|e| e.within(format!("faces[{i}]")))?);
        }
    }
    Ok(RawMesh {
        points: Some(points),
        faces: Some(faces),
        labels: Some(labels),
        vertices: None,
    })
}

fn face(c: &mut Cursor<'_>) -> Decoded<[u32; 3]> {
    c.fixed(3, "")?;
    let mut f = [0u32; 3];
    for (k, v) in f.iter_mut().enumerate() {
        let at = c.offset();
        let x = c.u64("")?;
        *v = u32::try_from(x).map_err(|_| {
            DecodeError::new(
                at,
                &format!("[{k}]"),
                format!("vertex {x} does not fit u32"),
            )
        })?;
    }
    Ok(f)
}

/// A vector of UINT64 (stamps), skipped.
fn skip_u64s(c: &mut Cursor<'_>, field: &str) -> Decoded<()> {
    let n = c.array_len(Scalar::U64.encoded(), field)?;
    let u = Tag::U64 as u8;
    if c.records(n, &mut Vec::new(), |r: &[u8; 9]| (r[0] == u).then_some(())) {
        return Ok(());
    }
    for i in 0..n {
        c.skip_scalar(Scalar::U64, "")
            .map_err(|e| e.within(format!("{field}[{i}]")))?;
    }
    Ok(())
}

/// Writes `m` with no colors and no stamps; `has_labels` when it has labels.
pub(super) fn write(w: &mut Writer, m: &DsgMesh) {
    let labels = m.labels.as_deref().unwrap_or(&[]);
    w.bool(false);
    w.bool(false);
    w.bool(!labels.is_empty());
    w.bool(false);
    w.array(m.points.len());
    for &p in &m.points {
        w.vec3_f32(p);
    }
    w.array(0); // colors
    w.array(0); // stamps
    w.array(labels.len());
    for &l in labels {
        w.u32(l);
    }
    w.array(0); // first-seen stamps
    w.array(m.faces.len());
    for f in &m.faces {
        w.array(3);
        for &v in f {
            w.u64(u64::from(v));
        }
    }
}
