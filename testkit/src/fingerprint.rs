//! Canonical text forms of archived segments, for tests that compare a writer's
//! incrementally built segments with fresh ones.

use std::collections::BTreeMap;
use ygg_store::index::KdTree;
use ygg_store::snapshot::{LayerSegment, Manifest, archive};

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
        "{} {} {} {:?}\nids {:?}\npoints {:?} {:?}\nparents {:?}\nchildren {:?} {:?}\n\
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
        s.child_offsets,
        s.children,
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
        s.layer_index.as_ref().map(tree),
        s.node_indexes
            .iter()
            .map(|n| (n.root, n.ids.clone(), tree(&n.tree)))
            .collect::<Vec<_>>(),
    )
}

/// A manifest in a canonical order.
pub fn manifest_fingerprint(m: &Manifest) -> String {
    fn sorted(map: &std::collections::HashMap<String, Vec<u32>>) -> BTreeMap<&String, &Vec<u32>> {
        map.iter().collect()
    }
    format!(
        "{} {} {:?} {:?} {:?}",
        m.version,
        m.generation,
        m.layers,
        sorted(&m.label_layers),
        sorted(&m.key_layers)
    )
}
