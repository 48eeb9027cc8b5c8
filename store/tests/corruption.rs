//! Bad snapshot bytes (truncated, bit-flipped, empty, foreign) give an error, never a
//! panic; bytes that still validate answer every query without panicking.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use ygg_store::index::KdTree;
use ygg_store::index::SpatialIndex;
use ygg_store::query::{self, Direction};
use ygg_store::snapshot::{
    ArchivedScene, FORMAT_VERSION, KnownParts, LayerSegment, Manifest, PointChunk, PointChunkRef,
    SegmentBytes, Structure, TreeChunk, TreeChunkRef, archive, validate_chunk, validate_layer,
    validate_manifest, validate_structure, validate_tree_chunk,
};
use ygg_store::{FeatureValue, NodeId, SceneGraph, SceneView, Scope, SnapshotFile};

/// A small but complete scene: every column of the layout is non-empty.
fn sample_scene() -> SceneGraph {
    let mut g = SceneGraph::new();
    let b = g.add_layer("building").unwrap();
    let r = g.add_layer("rooms").unwrap();
    let o = g.add_layer("objects").unwrap();
    g.add_layer_edge(b, r).unwrap();
    g.add_layer_edge(r, o).unwrap();
    g.add_node(NodeId(1), b).unwrap();
    g.enable_bounding_box(NodeId(1)).unwrap();
    for room in 0..3u64 {
        let rid = NodeId(100 + room);
        g.add_node(rid, r).unwrap();
        g.nest(NodeId(1), rid).unwrap();
        g.enable_bounding_box(rid).unwrap();
        g.set_feature(
            rid,
            "name",
            FeatureValue::from(format!("room{room}").as_str()),
        )
        .unwrap();
        for k in 0..5u64 {
            let id = NodeId(1000 + room * 10 + k);
            g.add_node(id, o).unwrap();
            g.set_geometry(
                id,
                vec![
                    [room as f32, k as f32, 0.5],
                    [room as f32 + 0.2, k as f32, 1.0],
                ],
            )
            .unwrap();
            g.add_label(id, ["chair", "light", "desk"][k as usize % 3])
                .unwrap();
            g.set_feature(id, "weight", FeatureValue::Float(k as f64))
                .unwrap();
            g.set_feature(id, "count", FeatureValue::Int(k as i64))
                .unwrap();
            g.set_feature(id, "on", FeatureValue::Bool(k % 2 == 0))
                .unwrap();
            g.nest(rid, id).unwrap();
            if k > 0 {
                g.add_edge(NodeId(id.0 - 1), id, "next").unwrap();
            }
        }
    }
    g
}

/// Runs every query; the point is that none of them panics on validated bytes.
fn exercise(file: &SnapshotFile) -> usize {
    let v = file.view();
    let mut n = 0;
    for l in v.layers() {
        n += v.layer_nodes(l).count();
        n += query::nodes_with_label(&v, Scope::Layer(l), "chair").len();
        let _ = v.layer_name(l);
        let _ = v.layer_children(l);
    }
    n += query::nodes_with_label(&v, Scope::Graph, "light").len();
    n += query::nodes_having(&v, Scope::Graph, &["weight", "on"]).len();
    n += query::edges_matching(&v, Scope::Graph, "next").len();
    for id in [1, 100, 101, 102, 1000, 1004, 1013, 1024] {
        let id = NodeId(id);
        n += query::subtree(&v, id).len();
        n += query::bfs(&v, id, Direction::Undirected).len();
        n += query::dfs(&v, id, Direction::Outgoing).len();
        n += query::edges_from(&v, id).len() + query::edges_to(&v, id).len();
        if let Some(node) = v.node(id) {
            n += v.points(node).len() + v.features(node).count() + v.labels(node).count();
            let _ = v.aabb(node);
        }
    }
    n += query::subgraph(&v, &[NodeId(1), NodeId(100), NodeId(1000)]).node_count();
    n
}

fn snapshot_bytes() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.ygg");
    sample_scene().save(&path).unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn intact_snapshot_opens_and_answers() {
    let bytes = snapshot_bytes();
    let file = SnapshotFile::from_bytes(&bytes, "intact").unwrap();
    assert!(exercise(&file) > 0);
    assert_eq!(file.view().node_count(), sample_scene().node_count());
}

#[test]
fn empty_foreign_and_truncated_files_are_errors() {
    let bytes = snapshot_bytes();
    assert!(SnapshotFile::from_bytes(&[], "empty").is_err());
    assert!(SnapshotFile::from_bytes(b"{\"nodes\": []}", "json").is_err());
    let mut wrong_version = bytes.clone();
    wrong_version[8] ^= 0xff;
    let err = SnapshotFile::from_bytes(&wrong_version, "v")
        .err()
        .expect("version mismatch");
    assert!(err.to_string().contains("format version"), "{err}");
    for cut in (0..bytes.len()).step_by(7) {
        assert!(
            SnapshotFile::from_bytes(&bytes[..cut], "truncated").is_err(),
            "cut at {cut} opened"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.ygg");
    std::fs::write(&empty, b"").unwrap();
    let err = SnapshotFile::open(&empty).err().expect("empty file");
    assert!(
        err.to_string().contains("empty.ygg"),
        "error names the file: {err}"
    );
    assert!(SnapshotFile::open(dir.path().join("missing.ygg")).is_err());
}

#[test]
fn thousands_of_random_corruptions_never_panic() {
    let bytes = snapshot_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
    let (mut opened, mut refused) = (0, 0);
    for round in 0..4000 {
        let mut b = bytes.clone();
        match round % 4 {
            0 => {
                let i = rng.gen_range(0..b.len());
                b[i] ^= 1 << rng.gen_range(0..8);
            }
            1 => {
                for _ in 0..rng.gen_range(2..16) {
                    let i = rng.gen_range(0..b.len());
                    b[i] = rng.r#gen();
                }
            }
            2 => {
                let i = rng.gen_range(0..b.len() - 8);
                let v: u64 = rng.r#gen::<u64>() % 4096;
                b[i..i + 8].copy_from_slice(&v.to_le_bytes());
            }
            _ => {
                let i = rng.gen_range(0..b.len() - 4);
                b[i..i + 4].copy_from_slice(&u32::MAX.to_le_bytes());
            }
        }
        match SnapshotFile::from_bytes(&b, "corrupt") {
            Ok(file) => {
                exercise(&file);
                opened += 1;
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                refused += 1;
            }
        }
    }
    // Both outcomes must occur: flips inside point data still validate, flips in the
    // structure are refused.
    assert!(
        opened > 100 && refused > 100,
        "opened {opened}, refused {refused}"
    );
}

/// Checks the cut of `manifest` (tampered by the caller) with `g`'s layer segments, as a
/// reader does: bytecheck of every segment, then `ArchivedScene::new`.
fn check_cut(g: &SceneGraph, structure: &Structure, manifest: &Manifest) -> Result<(), String> {
    let layers: Vec<SegmentBytes> = g.layers().map(|l| archive(&g.layer_segment(l))).collect();
    let manifest = archive(manifest);
    let manifest = validate_manifest(&manifest, "manifest").map_err(|e| e.to_string())?;
    let structure = archive(structure);
    let structure = validate_structure(&structure, "structure").map_err(|e| e.to_string())?;
    let layers = layers
        .iter()
        .map(|b| validate_layer(b, "layer").map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    ArchivedScene::new(manifest, structure, layers, Vec::new(), Vec::new()).map(|_| ())
}

#[test]
fn inconsistent_manifests_are_refused_naming_what_is_wrong() {
    let g = sample_scene();
    let m = g.manifest(1, 1);
    check_cut(&g, &g.structure(1), &m).expect("the intact cut is accepted");

    let mut s = g.structure(1);
    s.label_layers.insert("chair".into(), vec![99]);
    let e = check_cut(&g, &s, &m).unwrap_err();
    assert!(e.contains("graph index names an unknown layer"), "{e}");

    let mut s = g.structure(1);
    s.layers[0].children.push(99);
    let e = check_cut(&g, &s, &m).unwrap_err();
    assert!(e.contains("DAG edge to an unknown layer"), "{e}");

    let mut s = g.structure(1);
    let last = s.layers[2].children.clone();
    s.layers[2].children = s.layers[1].children.clone();
    s.layers[1].children = last;
    let e = check_cut(&g, &s, &m).unwrap_err();
    assert!(e.contains("is not mirrored"), "{e}");

    // Layers out of order: refused before any id is looked up by binary search.
    let mut s = g.structure(1);
    s.layers.swap(0, 1);
    let e = check_cut(&g, &s, &m).unwrap_err();
    assert!(e.contains("structure layers are not ascending"), "{e}");

    // A part listed twice, a structure of another generation, a manifest of other
    // layers.
    let mut s = g.structure(1);
    s.layers[1].parts.push(0);
    let e = check_cut(&g, &s, &m).unwrap_err();
    assert!(e.contains("a part twice"), "{e}");
    let e = check_cut(&g, &g.structure(2), &m).unwrap_err();
    assert!(
        e.contains("manifest names structure 1, structure 2 given"),
        "{e}"
    );
    let mut other = g.manifest(1, 1);
    other.layers.pop();
    let e = check_cut(&g, &g.structure(1), &other).unwrap_err();
    assert!(e.contains("not the 3 of its structure"), "{e}");
}

/// The sample scene's segments with every layer's point column split into chunks of 4
/// points (as a publishing writer splits a large layer), before archiving: the
/// manifest, the layer segments, and the chunks in layer and column order.
fn chunked_cut(g: &SceneGraph) -> ((Manifest, Structure), Vec<LayerSegment>, Vec<PointChunk>) {
    let mut layers = Vec::new();
    let mut chunks = Vec::new();
    for l in g.layers() {
        let mut s = g.layer_segment(l);
        if s.points.len() > 4 {
            for (i, c) in s.points.chunks(4).enumerate() {
                s.point_chunks.push(PointChunkRef {
                    generation: s.generation,
                    len: c.len() as u32,
                });
                chunks.push(PointChunk::new(l, 0, i, s.generation, c));
            }
            s.point_chunk_len = 4;
            s.points.clear();
        }
        layers.push(s);
    }
    ((g.manifest(1, 1), g.structure(1)), layers, chunks)
}

/// Archives and checks a cut as a reader does (bytecheck of every segment, then
/// `ArchivedScene::new`), then reads every node's points; the number of points read.
fn check_chunked_cut(
    head: &(SegmentBytes, SegmentBytes),
    layers: &[SegmentBytes],
    chunks: &[SegmentBytes],
) -> Result<usize, String> {
    let manifest = validate_manifest(&head.0, "manifest").map_err(|e| e.to_string())?;
    let structure = validate_structure(&head.1, "structure").map_err(|e| e.to_string())?;
    let layers = layers
        .iter()
        .map(|b| validate_layer(b, "layer").map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let chunks = chunks
        .iter()
        .map(|b| validate_chunk(b, "chunk").map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let view = ArchivedScene::new(manifest, structure, layers, chunks, Vec::new())?;
    let mut points = 0;
    for l in view.layers() {
        for n in view.layer_nodes(l) {
            points += view.points(n).iter().count();
        }
        if let Some(index) = view.layer_index(l) {
            points += index.len();
        }
    }
    Ok(points)
}

fn archive_cut(
    cut: &((Manifest, Structure), Vec<LayerSegment>, Vec<PointChunk>),
) -> (
    (SegmentBytes, SegmentBytes),
    Vec<SegmentBytes>,
    Vec<SegmentBytes>,
) {
    (
        (archive(&cut.0.0), archive(&cut.0.1)),
        cut.1.iter().map(archive).collect(),
        cut.2.iter().map(archive).collect(),
    )
}

#[test]
fn inconsistent_point_chunks_are_refused_naming_what_is_wrong() {
    let mut g = sample_scene();
    let objects = g.layer_by_name("objects").unwrap();
    g.enable_layer_index(objects).unwrap();
    let cut = chunked_cut(&g);
    assert!(cut.2.len() > 4, "the objects layer is chunked");
    let (m, l, c) = archive_cut(&cut);
    let points = check_chunked_cut(&m, &l, &c).expect("the intact cut is accepted");
    assert_eq!(points, 2 * 30, "every node's points and the layer index's");

    let e = check_chunked_cut(&m, &l, &c[..c.len() - 1]).unwrap_err();
    assert!(e.contains("names 8 point chunks, 7 given"), "{e}");

    let mut more = c.clone();
    more.push(c[0].clone());
    let e = check_chunked_cut(&m, &l, &more).unwrap_err();
    assert!(e.contains("point chunks given out of order"), "{e}");

    let mut swapped = c.clone();
    swapped.swap(0, 1);
    let e = check_chunked_cut(&m, &l, &swapped).unwrap_err();
    assert!(e.contains("point chunks given out of order"), "{e}");

    // A chunk of another generation (held from an older cut).
    let mut older = chunked_cut(&g);
    older.2[3].generation -= 1;
    let (_, _, stale) = archive_cut(&older);
    let e = check_chunked_cut(&m, &l, &stale).unwrap_err();
    assert!(e.contains("names chunk 3 at generation"), "{e}");

    // Heads that lie about their chunks.
    let head = |tamper: fn(&mut LayerSegment)| {
        let mut cut = chunked_cut(&g);
        tamper(&mut cut.1[2]);
        let (m, l, c) = archive_cut(&cut);
        check_chunked_cut(&m, &l, &c).unwrap_err()
    };
    let e = head(|s| s.point_chunk_len = 3);
    assert!(e.contains("a power of two"), "{e}");
    let e = head(|s| s.point_chunks[2].len = 3);
    assert!(e.contains("point chunk 2 of 8 holds 3 points"), "{e}");
    let e = head(|s| s.point_chunks.last_mut().unwrap().len = 0);
    assert!(e.contains("holds 0 points"), "{e}");
    let e = head(|s| s.points.push([0.0; 3]));
    assert!(e.contains("also holds points inline"), "{e}");
    let e = head(|s| s.point_offsets.last_mut().map(|o| *o += 1).unwrap());
    assert!(e.contains("point_offsets"), "{e}");
}

/// Joins an archived chunked cut as a reader's next cut does (`ArchivedScene::rejoin`),
/// taking the structure and the layers flagged in `known` as checked; the number of
/// points the view reads.
fn rejoin_chunked_cut(
    head: &(SegmentBytes, SegmentBytes),
    layers: &[SegmentBytes],
    chunks: &[SegmentBytes],
    known: &[bool],
) -> Result<usize, String> {
    let manifest = validate_manifest(&head.0, "manifest").map_err(|e| e.to_string())?;
    let structure = validate_structure(&head.1, "structure").map_err(|e| e.to_string())?;
    let layers: Vec<_> = layers
        .iter()
        .map(|b| validate_layer(b, "layer").unwrap())
        .collect();
    let chunks: Vec<_> = chunks
        .iter()
        .map(|b| validate_chunk(b, "chunk").unwrap())
        .collect();
    let known = KnownParts {
        structure: true,
        layers: known,
    };
    let view = ArchivedScene::rejoin(manifest, structure, layers, chunks, Vec::new(), known)?;
    Ok(view
        .layers()
        .flat_map(|l| view.layer_nodes(l))
        .map(|n| view.points(n).len())
        .sum())
}

#[test]
fn a_rejoin_reads_chunks_past_known_layers_and_refuses_one_given_for_a_known_layer() {
    let g = sample_scene();
    let cut = chunked_cut(&g);
    let chunked: Vec<bool> = cut.1.iter().map(|s| !s.point_chunks.is_empty()).collect();
    assert_eq!(
        chunked,
        [false, false, true],
        "only the objects layer is chunked"
    );
    let (m, l, c) = archive_cut(&cut);
    // The building and rooms layers known, as a reader knows unchanged chunkless layers.
    let known = [true, true, false];
    assert_eq!(rejoin_chunked_cut(&m, &l, &c, &known), Ok(30));
    assert_eq!(rejoin_chunked_cut(&m, &l, &c, &[]), Ok(30), "nothing known");

    // A chunk given for the rooms layer, which names none: refused whether it comes
    // before the objects layer's chunks or after them.
    let rooms = g.layer_by_name("rooms").unwrap();
    let stray = archive(&PointChunk::new(
        rooms,
        0,
        0,
        cut.1[1].generation,
        &[[0.0; 3]],
    ));
    let mut before = vec![stray.clone()];
    before.extend(c.iter().cloned());
    let e = rejoin_chunked_cut(&m, &l, &before, &known).unwrap_err();
    assert!(
        e.contains("part 0 of layer 1 names 0 point chunks, 1 given"),
        "{e}"
    );
    let mut after = c.clone();
    after.push(stray);
    let e = rejoin_chunked_cut(&m, &l, &after, &known).unwrap_err();
    assert!(e.contains("point chunks given out of order"), "{e}");
}

/// Damages `b` at a random place: one bit flipped, or a 4-byte word overwritten with
/// `u32::MAX` or a small number (a length or an offset gone wrong).
fn damage(b: &mut [u8], rng: &mut ChaCha8Rng) {
    let i = rng.gen_range(0..b.len() - 4);
    match rng.gen_range(0..3) {
        0 => b[i] ^= 1 << rng.gen_range(0..8),
        1 => b[i..i + 4].copy_from_slice(&u32::MAX.to_le_bytes()),
        _ => b[i..i + 4].copy_from_slice(&(rng.r#gen::<u32>() % 64).to_le_bytes()),
    }
}

/// Runs 2,000 random damages through `check` (which must not panic) and asserts that both
/// outcomes occur often: damage inside coordinates still validates, damage in the
/// structure is refused with a message.
fn damages_are_refused_or_harmless(
    seed: u64,
    mut check: impl FnMut(&mut ChaCha8Rng) -> Result<usize, String>,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut accepted, mut refused) = (0, 0);
    for _ in 0..2000 {
        match check(&mut rng) {
            Ok(_) => accepted += 1,
            Err(e) => {
                assert!(!e.is_empty());
                refused += 1;
            }
        }
    }
    assert!(
        accepted > 100 && refused > 100,
        "accepted {accepted}, refused {refused}"
    );
}

#[test]
fn random_corruptions_of_point_chunks_never_panic() {
    let mut g = sample_scene();
    let objects = g.layer_by_name("objects").unwrap();
    g.enable_layer_index(objects).unwrap();
    let (m, l, c) = archive_cut(&chunked_cut(&g));
    damages_are_refused_or_harmless(0xC4, |rng| {
        let mut chunks = c.clone();
        let k = rng.gen_range(0..chunks.len());
        damage(&mut chunks[k], rng);
        check_chunked_cut(&m, &l, &chunks)
    });
}

/// The sample scene's segments with every index tree moved to a tree chunk (as a
/// publishing writer sends a large one): the manifest, the layer segments, and the tree
/// chunks in layer order, then slot order (the layer index's base tree at slot 0, node
/// index `i`'s tree at slot `1 + i`).
fn tree_chunked_cut(g: &SceneGraph) -> ((Manifest, Structure), Vec<LayerSegment>, Vec<TreeChunk>) {
    let mut layers = Vec::new();
    let mut trees = Vec::new();
    let empty = || KdTree::new_from_entries(&[]).unwrap();
    for l in g.layers() {
        let mut s = g.layer_segment(l);
        let generation = s.generation;
        let mut chunk = |slot: u32, items: u32, tree: KdTree| {
            let r = TreeChunkRef {
                generation,
                points: tree.size() as u32,
            };
            trees.push(TreeChunk {
                version: FORMAT_VERSION,
                layer: l.0,
                part: 0,
                slot,
                generation,
                items,
                tree,
            });
            r
        };
        if let Some(index) = s.layer_index.as_mut() {
            let tree = std::mem::replace(&mut index.tree, empty());
            index.tree_chunk = Some(chunk(0, index.base_rows, tree));
        }
        for (i, index) in s.node_indexes.iter_mut().enumerate() {
            let tree = std::mem::replace(&mut index.tree, empty());
            index.tree_chunk = Some(chunk(1 + i as u32, index.ids.len() as u32, tree));
        }
        layers.push(s);
    }
    ((g.manifest(1, 1), g.structure(1)), layers, trees)
}

/// Archives and checks a tree-chunked cut as a reader does, then runs every spatial
/// query on every layer index; the number of points the indexes hold.
fn check_tree_chunked_cut(
    cut: &((Manifest, Structure), Vec<LayerSegment>, Vec<TreeChunk>),
    tamper: impl FnOnce(&mut Vec<SegmentBytes>),
) -> Result<usize, String> {
    let manifest = archive(&cut.0.0);
    let structure = archive(&cut.0.1);
    let structure = validate_structure(&structure, "structure").map_err(|e| e.to_string())?;
    let layers: Vec<SegmentBytes> = cut.1.iter().map(archive).collect();
    let mut trees: Vec<SegmentBytes> = cut.2.iter().map(archive).collect();
    tamper(&mut trees);
    let manifest = validate_manifest(&manifest, "manifest").map_err(|e| e.to_string())?;
    let layers = layers
        .iter()
        .map(|b| validate_layer(b, "layer").map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let trees = trees
        .iter()
        .map(|b| validate_tree_chunk(b, "tree chunk").map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let view = ArchivedScene::new(manifest, structure, layers, Vec::new(), trees)?;
    let mut points = 0;
    for l in view.layers() {
        if let Some(index) = view.layer_index(l) {
            points += index.len();
            let _ = query::nearest_nodes(&view, Scope::Layer(l), [0.5, 0.5, 0.5], 3);
            let _ = query::nodes_within_radius(&view, Scope::Layer(l), [0.5, 0.5, 0.5], 2.0);
        }
        for n in view.layer_nodes(l) {
            let id = view.node_id(n);
            if let Some(index) = view.node_index(id) {
                points += index.len();
                let _ = query::nearest_in_subtree(&view, id, [0.5, 0.5, 0.5], 3);
            }
        }
    }
    Ok(points)
}

#[test]
fn inconsistent_tree_chunks_are_refused_naming_what_is_wrong() {
    let g = tree_chunked_scene();
    let cut = tree_chunked_cut(&g);
    assert_eq!(
        cut.2.len(),
        3,
        "the objects layer's tree and two rooms' are chunks"
    );
    let points = check_tree_chunked_cut(&cut, |_| ()).expect("the intact cut is accepted");
    assert_eq!(
        points,
        30 + 2 * 10,
        "the layer index holds every point of the layer, each room's its objects'"
    );

    let e = check_tree_chunked_cut(&cut, |t| t.clear()).unwrap_err();
    assert!(e.contains("names tree chunk 1, not given"), "{e}");
    let e = check_tree_chunked_cut(&cut, |t| t.push(t[0].clone())).unwrap_err();
    assert!(e.contains("tree chunks given out of order"), "{e}");
    // The two rooms' trees swapped: refused, as given out of order.
    let e = check_tree_chunked_cut(&cut, |t| t.swap(0, 1)).unwrap_err();
    assert!(e.contains("tree chunks given out of order"), "{e}");

    // A tree of another generation (held from an older cut), of another layer, or with
    // items past the index's base rows.
    let chunk = |tamper: fn(&mut TreeChunk)| {
        let mut cut = tree_chunked_cut(&g);
        let last = cut.2.len() - 1;
        tamper(&mut cut.2[last]);
        check_tree_chunked_cut(&cut, |_| ()).unwrap_err()
    };
    let e = chunk(|t| t.generation -= 1);
    assert!(e.contains("names tree 0 at generation"), "{e}");
    // Chunks are found by (layer, part, slot): one that names another layer is not the
    // one its part names.
    let e = chunk(|t| t.layer += 1);
    assert!(e.contains("names tree chunk 0, not given"), "{e}");
    let e = chunk(|t| t.items += 1);
    assert!(e.contains("items below"), "{e}");
    let e = chunk(|t| t.items = 0);
    assert!(e.contains("tree chunk"), "{e}");

    // A head that lies about its tree.
    let mut lying = tree_chunked_cut(&g);
    let index = lying
        .1
        .iter_mut()
        .find_map(|s| s.layer_index.as_mut())
        .unwrap();
    index.tree_chunk.as_mut().unwrap().points += 1;
    let e = check_tree_chunked_cut(&lying, |_| ()).unwrap_err();
    assert!(e.contains("tree chunk's point count differs"), "{e}");
    // A node index that names a chunk yet keeps a tree inline, or names a chunk of
    // another point count.
    let mut lying = tree_chunked_cut(&g);
    let rooms = lying
        .1
        .iter_mut()
        .find(|s| !s.node_indexes.is_empty())
        .unwrap();
    let tree = std::mem::replace(&mut lying.2[0].tree, KdTree::new_from_entries(&[]).unwrap());
    rooms.node_indexes[0].tree = tree;
    let e = check_tree_chunked_cut(&lying, |_| ()).unwrap_err();
    assert!(
        e.contains("travels as a chunk, yet the segment holds one"),
        "{e}"
    );
    let mut lying = tree_chunked_cut(&g);
    let rooms = lying
        .1
        .iter_mut()
        .find(|s| !s.node_indexes.is_empty())
        .unwrap();
    rooms.node_indexes[1].tree_chunk.as_mut().unwrap().points -= 1;
    let e = check_tree_chunked_cut(&lying, |_| ()).unwrap_err();
    assert!(e.contains("slot 2") && e.contains("9 points"), "{e}");
}

/// [`sample_scene`] with a layer index on its objects and a node index on two rooms.
fn tree_chunked_scene() -> SceneGraph {
    let mut g = sample_scene();
    let objects = g.layer_by_name("objects").unwrap();
    g.enable_layer_index(objects).unwrap();
    g.enable_node_index(NodeId(100)).unwrap();
    g.enable_node_index(NodeId(102)).unwrap();
    g
}

#[test]
fn random_corruptions_of_tree_chunks_never_panic() {
    let g = tree_chunked_scene();
    let cut = tree_chunked_cut(&g);
    for at in 0..cut.2.len() {
        damages_are_refused_or_harmless(0x7E + at as u64, |rng| {
            check_tree_chunked_cut(&cut, |trees| damage(&mut trees[at], rng))
        });
    }
}

#[test]
fn a_layer_whose_rows_by_parent_lie_is_refused_naming_what_is_wrong() {
    let g = sample_scene();
    let objects = g.layer_by_name("objects").unwrap();
    let refused = |tamper: fn(&mut LayerSegment)| {
        let mut s = g.layer_segment(objects);
        tamper(&mut s);
        validate_layer(&archive(&s), "objects")
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let intact = g.layer_segment(objects);
    assert_eq!(intact.by_parent.len(), 15, "every object is nested");
    assert!(validate_layer(&archive(&intact), "objects").is_ok());
    let e = refused(|s| {
        s.by_parent.pop();
    });
    assert!(
        e.contains("by_parent lists 14 rows, 15 rows have a parent"),
        "{e}"
    );
    let e = refused(|s| s.by_parent.swap(0, 5));
    assert!(e.contains("not ascending by (parent, row)"), "{e}");
    let e = refused(|s| s.by_parent[3] = 40);
    assert!(e.contains("by_parent[3] = 40 is out of range"), "{e}");
    let e = refused(|s| s.by_parent[1] = s.by_parent[0]);
    assert!(e.contains("by_parent[1]"), "{e}");
    let e = refused(|s| s.parents[0] = u64::MAX);
    assert!(e.contains("15 rows, 14 rows have a parent"), "{e}");
}
