//! Canonical text forms of archived segments, for tests that compare a writer's
//! incrementally built segments with fresh ones, and of the layers of any view, for
//! tests that compare graphs whose layer ids may differ (matched by layer name).

use std::collections::BTreeMap;
use ygg_store::index::KdTree;
use ygg_store::query;
use ygg_store::snapshot::{LayerSegment, Manifest, Structure, archive};
use ygg_store::{LayerId, SceneView};

/// A layer segment with every string index resolved, in a canonical order: equal for
/// segments that hold the same rows whatever the order of their string tables.
pub fn segment_fingerprint(s: &LayerSegment) -> String {
    let strs = |v: &[u32]| {
        v.iter()
            .map(|&i| s.strings[i as usize].as_str())
            .collect::<Vec<_>>()
    };
    let features: Vec<String> = (0..s.feature_keys.len())
        .map(|i| {
            let key = &s.strings[s.feature_keys[i] as usize];
            match s.feature_kinds[i] {
                0 => format!("{key}=str:{}", s.strings[s.feature_bits[i] as usize]),
                kind => format!("{key}={kind}:{}", s.feature_bits[i]),
            }
        })
        .collect();
    let postings = |index: &std::collections::HashMap<String, [u32; 2]>, postings: &[u32]| {
        index
            .iter()
            .map(|(term, [a, b])| (term.clone(), postings[*a as usize..*b as usize].to_vec()))
            .collect::<BTreeMap<_, _>>()
    };
    let tree = |t: &KdTree| archive(t).to_vec();
    format!(
        "{} {} {} {:?}\nids {:?}\npoints {:?} {:?}\nparents {:?}\nby parent {:?}\n\
         out {:?} {:?} {:?}\nin {:?} {:?} {:?}\nlabels {:?} {:?}\nfeatures {:?} {features:?}\n\
         boxes {:?} {:?}\nlabel index {:?}\nkey index {:?}\nlayer index {:?}\nnode indexes {:?}",
        s.version,
        s.layer,
        s.generation,
        s.name,
        s.ids,
        s.point_offsets,
        s.points,
        s.parents,
        s.by_parent,
        s.out_offsets,
        s.out_targets,
        strs(&s.out_descriptions),
        s.in_offsets,
        s.in_sources,
        strs(&s.in_descriptions),
        s.label_offsets,
        strs(&s.labels),
        s.feature_offsets,
        s.aabb_rows,
        s.aabbs,
        postings(&s.label_index, &s.label_postings),
        postings(&s.key_index, &s.key_postings),
        s.layer_index_entries(),
        s.node_indexes
            .iter()
            .map(|n| (n.root, n.ids.clone(), tree(&n.tree)))
            .collect::<Vec<_>>(),
    )
}

/// A manifest in a canonical order.
pub fn manifest_fingerprint(m: &Manifest) -> String {
    format!(
        "{} {} {} {:?}",
        m.version, m.generation, m.structure, m.layers
    )
}

/// A structure in a canonical order, but for its generation.
pub fn structure_fingerprint(s: &Structure) -> String {
    fn sorted(map: &std::collections::HashMap<String, Vec<u32>>) -> BTreeMap<&String, &Vec<u32>> {
        map.iter().collect()
    }
    format!(
        "{} {:?} {:?} {:?}",
        s.version,
        s.layers,
        sorted(&s.label_layers),
        sorted(&s.key_layers)
    )
}

/// The content of one layer of any view, by name, in a canonical order: what its
/// archived segment holds (every node's points, parent, box, labels, features, edges,
/// node index members; a node's children are the rows naming it as parent in the
/// layers below), with the layer name of every node a row refers to (a row naming a node that moved to another layer is rebuilt, so that
/// counts as a change). `with_dag` adds the names of the layer's DAG parents and
/// children (which are not part of its segment).
///
/// Two views' fingerprints of a layer are equal when the layer holds the same content,
/// whatever the layer ids.
pub fn layer_fingerprint<V: SceneView>(v: &V, layer: LayerId, with_dag: bool) -> String {
    let name = |l: LayerId| v.layer_name(l).unwrap_or("?").to_owned();
    let layer_of = |id| v.node(id).map(|n| name(v.node_layer(n)));
    let mut out = format!(
        "layer {:?} index {}\n",
        name(layer),
        v.layer_index(layer).is_some()
    );
    if with_dag {
        let mut parents: Vec<_> = v.layer_parents(layer).into_iter().map(name).collect();
        let mut children: Vec<_> = v.layer_children(layer).into_iter().map(name).collect();
        parents.sort_unstable();
        children.sort_unstable();
        out += &format!("  dag {parents:?} {children:?}\n");
    }
    let mut nodes: Vec<_> = v.layer_nodes(layer).map(|n| v.node_id(n)).collect();
    nodes.sort_unstable();
    for id in nodes {
        let n = v.node(id).expect("listed node resolves");
        let mut labels: Vec<_> = v.labels(n).collect();
        labels.sort_unstable();
        let mut features: Vec<_> = v.features(n).map(|(k, f)| format!("{k}={f:?}")).collect();
        features.sort_unstable();
        let out_edges: Vec<_> = v.out_edges(n).collect();
        let in_edges: Vec<_> = v.in_edges(n).collect();
        let index = v.has_node_index(id).then(|| {
            query::subtree(v, id)
                .into_iter()
                .map(|m| (m, layer_of(m), v.node(m).map(|m| v.points(m).to_vec())))
                .collect::<Vec<_>>()
        });
        out += &format!(
            "  {id} pts {:?} parent {:?} box {:?} labels {labels:?} \
             features {features:?} out {out_edges:?} in {in_edges:?} index {index:?}\n",
            v.points(n),
            v.parent(n).map(|p| (p, layer_of(p))),
            v.aabb(n),
        );
    }
    out
}

/// [`layer_fingerprint`] of every layer, by layer name: equal maps (with `with_dag`)
/// mean equal graphs up to layer ids.
pub fn layer_fingerprints<V: SceneView>(v: &V, with_dag: bool) -> BTreeMap<String, String> {
    v.layers()
        .map(|l| {
            (
                v.layer_name(l).unwrap_or("?").to_owned(),
                layer_fingerprint(v, l, with_dag),
            )
        })
        .collect()
}

/// Names of the layers whose [`layer_fingerprint`] (without the DAG) differs between
/// `a` and `b`, or that only `b` has: the layers a publish of `b` after `a` must resend.
pub fn changed_layers<A: SceneView, B: SceneView>(a: &A, b: &B) -> Vec<String> {
    let before = layer_fingerprints(a, false);
    layer_fingerprints(b, false)
        .into_iter()
        .filter(|(name, fp)| before.get(name) != Some(fp))
        .map(|(name, _)| name)
        .collect()
}
