//! A publishing writer patches a layer index instead of rebuilding it, and folds the patch
//! into a new base tree past its budget (`snapshot/publish/layer_index_update.rs`).

use ygg_store::snapshot::SegmentCache;
use ygg_store::{LayerId, NodeId, SceneGraph};

/// A layer of `nodes` nodes with `per` points each, indexed.
fn indexed_layer(nodes: u64, per: usize) -> (SceneGraph, LayerId) {
    let mut g = SceneGraph::new();
    let l = g.add_layer("mesh").unwrap();
    for i in 0..nodes {
        g.add_node(NodeId(i), l).unwrap();
        let points = (0..per).map(|k| [i as f32, k as f32, 0.0]).collect();
        g.set_geometry(NodeId(i), points).unwrap();
    }
    g.enable_layer_index(l).unwrap();
    (g, l)
}

fn index(cache: &mut SegmentCache, g: &mut SceneGraph, l: LayerId) -> (u32, Vec<u32>) {
    let s = cache.layer_segment(g, l);
    let i = s.layer_index.as_ref().unwrap();
    assert_eq!(
        s.layer_index_entries(),
        g.layer_segment(l).layer_index_entries()
    );
    (i.base_rows, i.patched.clone())
}

#[test]
fn moves_and_appends_patch_the_index_until_the_budget_folds_it() {
    let (mut g, l) = indexed_layer(100, 50);
    let mut cache = SegmentCache::new();
    assert_eq!(index(&mut cache, &mut g, l), (100, vec![]));
    // A node moved: its row is patched, the base tree stays.
    let moved: Vec<_> = (0..50).map(|k| [7.5, k as f32, 1.0]).collect();
    g.set_geometry(NodeId(7), moved.clone()).unwrap();
    assert_eq!(index(&mut cache, &mut g, l), (100, vec![7]));
    // Moved again: still one row; a label change patches nothing.
    g.set_geometry(NodeId(7), moved.iter().map(|p| [p[0], p[1], 2.0]).collect())
        .unwrap();
    g.add_label(NodeId(8), "chair").unwrap();
    assert_eq!(index(&mut cache, &mut g, l), (100, vec![7]));
    // Appended rows are patched; removed ones leave the list.
    g.add_node(NodeId(500), l).unwrap();
    g.set_geometry(NodeId(500), vec![[0.0; 3]]).unwrap();
    g.add_node(NodeId(501), l).unwrap();
    assert_eq!(index(&mut cache, &mut g, l), (100, vec![7, 100]));
    g.remove_node(NodeId(501)).unwrap();
    g.remove_node(NodeId(500)).unwrap();
    assert_eq!(index(&mut cache, &mut g, l), (100, vec![7]));
    // Past the budget (1024 live points: 21 rows of 50) the index is folded into a
    // new base.
    let mut folded_at = None;
    for i in 10..40 {
        g.set_geometry(NodeId(i), vec![[i as f32, 0.5, 3.0]; 50])
            .unwrap();
        let (base_rows, patched) = index(&mut cache, &mut g, l);
        assert_eq!(base_rows, 100);
        if patched.is_empty() {
            folded_at = Some(i);
            break;
        }
    }
    // Rows 7 and 10..=29: 21 rows, 1,050 live points.
    assert_eq!(folded_at, Some(29), "folded past 1,024 live points");
}

#[test]
fn one_object_moved_back_and_forth_never_folds_its_layer_index() {
    // The office's median object: 567 points, in a room of a few thousand.
    let (mut g, l) = indexed_layer(10, 600);
    let mut cache = SegmentCache::new();
    index(&mut cache, &mut g, l);
    let original: Vec<_> = (0..600).map(|k| [3.0, k as f32, 0.0]).collect();
    for step in 0..20 {
        let dz = if step % 2 == 0 { 0.5 } else { 0.0 };
        let moved = original.iter().map(|p| [p[0], p[1], p[2] + dz]).collect();
        g.set_geometry(NodeId(3), moved).unwrap();
        assert_eq!(index(&mut cache, &mut g, l), (10, vec![3]), "step {step}");
    }
}
