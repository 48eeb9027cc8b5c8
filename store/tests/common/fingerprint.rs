//! A canonical text of everything a view tells, for comparing backends and cuts.

use ygg_store::SceneView;

/// Everything a view can tell, in a canonical order: equal fingerprints mean equal graphs.
pub fn fingerprint<V: SceneView>(v: &V) -> String {
    let mut out = String::new();
    for l in v.layers() {
        out += &format!(
            "layer {l} {:?} parents {:?} children {:?}\n",
            v.layer_name(l),
            v.layer_parents(l),
            v.layer_children(l)
        );
        let mut nodes: Vec<_> = v.layer_nodes(l).map(|n| v.node_id(n)).collect();
        nodes.sort_unstable();
        for id in nodes {
            let n = v.node(id).expect("listed node resolves");
            let mut labels: Vec<_> = v.labels(n).collect();
            labels.sort_unstable();
            let mut features: Vec<_> = v.features(n).map(|(k, f)| format!("{k}={f:?}")).collect();
            features.sort_unstable();
            let out_edges: Vec<_> = v.out_edges(n).collect();
            let in_edges: Vec<_> = v.in_edges(n).collect();
            out += &format!(
                "  {id} pts {:?} parent {:?} children {:?} box {:?} labels {labels:?} features {features:?} out {out_edges:?} in {in_edges:?}\n",
                v.points(n),
                v.parent(n),
                v.children(n).collect::<Vec<_>>(),
                v.aabb(n),
            );
        }
    }
    out
}
