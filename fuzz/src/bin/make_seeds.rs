//! Writes the seed corpus of every fuzz target into `fuzz/corpus/<target>/seed-*`:
//! `cargo run --manifest-path fuzz/Cargo.toml --bin make_seeds` (from the repository root).
//! Seeds are small valid inputs, so that libFuzzer starts from the shapes the decoders
//! accept rather than from random bytes.

use std::path::Path;

use ygg_dsg::office::{OfficeParams, generate};
use ygg_ros2::DsgUpdate;
use ygg_store::recording::{CutToRecord, RecordedSegment, Recording, RecordingOptions, RecordingWriter};
use ygg_store::{FeatureValue, NodeId, SceneGraph, SceneView};
use ygg_store::snapshot::{STRUCTURE_SEGMENT_ID, part_segment_id};
use ygg_transport::ManifestEntry;
use ygg_transport::protocol::{
    MANIFEST_LAYER_ID, SegmentHeader, SegmentKind, encode_manifest_prefix, manifest_prefix_len,
};

/// A few layers with every column in use: points, edges, nesting, labels, features, an
/// exact box, a layer index and a node index.
fn small_graph() -> Result<SceneGraph, Box<dyn std::error::Error>> {
    let mut g = SceneGraph::new();
    let rooms = g.add_layer("rooms")?;
    let objects = g.add_layer("objects")?;
    let mesh = g.add_layer("mesh")?;
    g.add_layer_edge(rooms, objects)?;
    g.add_layer_edge(objects, mesh)?;
    g.add_node(NodeId(1), rooms)?;
    g.enable_bounding_box(NodeId(1))?;
    for i in 0..4u64 {
        let object = NodeId(10 + i);
        g.add_node(object, objects)?;
        g.add_label(object, if i % 2 == 0 { "chair" } else { "light" })?;
        g.set_feature(object, "score", FeatureValue::Float(i as f64 * 0.5))?;
        g.set_feature(object, "name", FeatureValue::Str(format!("o{i}")))?;
        g.nest(NodeId(1), object)?;
        let part = NodeId(100 + i);
        g.add_node(part, mesh)?;
        g.set_geometry(part, vec![[i as f32, 1.0, 0.5], [i as f32 + 0.3, 1.2, 0.9]])?;
        g.nest(object, part)?;
        if i > 0 {
            g.add_edge(NodeId(9 + i), object, "near")?;
        }
    }
    g.enable_layer_index(mesh)?;
    g.enable_node_index(NodeId(10))?;
    Ok(g)
}

fn header(kind: SegmentKind, layer_id: u64, generation: u64, len: usize) -> Vec<u8> {
    let h = SegmentHeader::new(kind, layer_id, 1, generation, len as u64, 0);
    let mut out = Vec::new();
    out.extend_from_slice(&h.magic.to_le_bytes());
    out.extend_from_slice(&h.version.to_le_bytes());
    out.extend_from_slice(&h.kind.to_le_bytes());
    out.extend_from_slice(&h.flags.to_le_bytes());
    out.extend_from_slice(&h.reserved.to_le_bytes());
    out.extend_from_slice(&h.layer_id.to_le_bytes());
    out.extend_from_slice(&h.session.to_le_bytes());
    out.extend_from_slice(&h.generation.to_le_bytes());
    out.extend_from_slice(&h.len.to_le_bytes());
    out.extend_from_slice(&h.published_unix_ns.to_le_bytes());
    out
}

fn write(target: &str, name: &str, bytes: &[u8]) -> std::io::Result<()> {
    let dir = Path::new("fuzz/corpus").join(target);
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join(format!("seed-{name}")), bytes)
}

/// Appends `g` as cut `generation` of `recording`: every layer in one part, every
/// segment of that generation.
fn record_cut(
    recording: &mut RecordingWriter,
    g: &SceneGraph,
    generation: u64,
) -> Result<(), Box<dyn std::error::Error>> {
    let archived = g.to_segments();
    let mut segments: Vec<RecordedSegment<'_>> = g
        .layers()
        .zip(&archived.layers)
        .map(|(layer, bytes)| RecordedSegment {
            id: part_segment_id(layer, 0).expect("a small layer id"),
            generation,
            bytes,
        })
        .collect();
    segments.push(RecordedSegment {
        id: STRUCTURE_SEGMENT_ID,
        generation,
        bytes: &archived.structure,
    });
    segments.sort_by_key(|s| s.id);
    recording.append_cut(&CutToRecord {
        generation,
        session: 1,
        writer_unix_ns: generation * 1_000_000,
        manifest: &archived.manifest,
        segments,
    })?;
    Ok(())
}

/// A recording of two cuts of `g` (the second after a move), as one file's bytes.
fn recording_seed(g: &SceneGraph) -> Result<Vec<u8>, Box<dyn std::error::Error>> {
    let dir = tempfile::tempdir()?;
    let mut recording = RecordingWriter::create(dir.path(), RecordingOptions::default())?;
    record_cut(&mut recording, g, 1)?;
    let mut moved = g.clone();
    moved.set_geometry(NodeId(100), vec![[5.0, 5.0, 0.5]])?;
    record_cut(&mut recording, &moved, 2)?;
    drop(recording);
    let opened = Recording::open(dir.path())?;
    assert_eq!(opened.cuts().len(), 2);
    opened.scene(1)?;
    Ok(std::fs::read(dir.path().join("00000001.ygr"))?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let g = small_graph()?;
    write("open_recording", "two-cuts", &recording_seed(&g)?)?;
    let file = Path::new("fuzz/corpus/open_ygg/seed-small.ygg");
    std::fs::create_dir_all(file.parent().expect("a folder"))?;
    g.save(file)?;

    let archived = g.to_segments();
    let mut entries = Vec::new();
    for (layer, bytes) in g.layers().zip(&archived.layers) {
        let id = part_segment_id(layer, 0).expect("a small layer id");
        let mut seed = header(SegmentKind::Layer, id, 1, bytes.len());
        seed.extend_from_slice(bytes);
        write("received_segment", &format!("layer{}", layer.0), &seed)?;
        entries.push(ManifestEntry {
            layer_id: id,
            generation: 1,
        });
    }
    let mut seed = header(SegmentKind::Layer, STRUCTURE_SEGMENT_ID, 1, archived.structure.len());
    seed.extend_from_slice(&archived.structure);
    write("received_segment", "structure", &seed)?;
    entries.push(ManifestEntry {
        layer_id: STRUCTURE_SEGMENT_ID,
        generation: 1,
    });
    let manifest = archived.manifest;
    let mut prefix = vec![0; manifest_prefix_len(entries.len())];
    encode_manifest_prefix(&entries, &mut prefix);
    let mut bytes = header(
        SegmentKind::Manifest,
        MANIFEST_LAYER_ID,
        1,
        prefix.len() + manifest.len(),
    );
    bytes.extend_from_slice(&prefix);
    bytes.extend_from_slice(&manifest);
    write("received_segment", "manifest", &bytes)?;

    let mut office = generate(OfficeParams {
        seed: 7,
        scale: 0.01,
    });
    office.mesh = None;
    write("dsg_json", "office.json", &ygg_dsg::to_json_bytes(&office))?;
    write("dsg_binary", "office.sparkdsg", &ygg_dsg::to_binary_bytes(&office)?)?;
    write("dsg_binary", "office.body", &ygg_dsg::to_binary_body(&office)?)?;

    // dsg_update: the pick byte 1 is plain CDR, little-endian (what rmw sends).
    let full = DsgUpdate {
        layer_contents: ygg_dsg::to_binary_body(&office)?,
        full_update: true,
        ..DsgUpdate::default()
    };
    let mut moved = office.clone();
    moved.nodes[3].position[2] += 0.5;
    let step = ygg_dsg::update_between(&office, &moved);
    let incremental = DsgUpdate {
        layer_contents: ygg_dsg::to_binary_body(&step.part)?,
        deleted_nodes: vec![office.nodes[5].id],
        deleted_edges: step.deleted_edges,
        sequence_number: 1,
        ..DsgUpdate::default()
    };
    for (name, message) in [("full", full), ("incremental", incremental)] {
        write("dsg_update", name, &[&[1], &message.to_cdr()[..]].concat())?;
    }

    for (name, line) in [
        ("nearest", r#"{"op":"nearest_object","point":[5,5,1]}"#),
        ("within", r#"{"op":"objects_within","point":[5,5,1],"radius":1.5}"#),
        (
            "visible",
            r#"{"op":"visible_objects","eye":[5,5,1],"dir":[1,0,0],"half_angle_deg":45,"range":6}"#,
        ),
        ("label", r#"{"op":"objects_with_label","label":"light"}"#),
    ] {
        write("query_line", name, line.as_bytes())?;
    }
    Ok(())
}
