//! Spark-DSG JSON import: typed parse, then checks and conversion to [`DsgGraph`].

use std::collections::{BTreeMap, BTreeSet};

use rustc_hash::{FxHashMap, FxHashSet};

use crate::diag;
use crate::error::DsgImportError;
use crate::model::{
    DsgAabb, DsgEdge, DsgGraph, DsgLayer, DsgMesh, DsgNode, DsgParentEdge, DsgVersion, LayerKey,
    NodeKind,
};
use crate::progress::{ImportPhase, ImportProgress};
use crate::raw::{Num, RawBox, RawFile, RawMesh, RawNode};
use crate::report::{DropClass, ImportOptions, ImportReport, Imported};
use crate::symbol::{NodeSymbol, describe_id, looks_like_symbol};

/// Parses a Spark-DSG JSON document (v1.1.x or legacy v1.0) into a [`DsgGraph`].
///
/// `source_name` is used in error messages and stored as [`DsgGraph::source`].
/// Node ids are read as u64 exactly. Fields the graph does not need (colors, stamps,
/// frontier data, ...) are skipped without being materialised.
///
/// # Errors
/// [`DsgImportError`] for malformed JSON (with line and column), wrong types, unknown
/// layers or attribute types, duplicate node ids, dangling / duplicate / self edges,
/// non-finite coordinates, and out-of-range mesh indices. Never panics.
///
/// # Examples
/// ```
/// let json = br#"{"SPARK_DSG_header":{"project_name":"main","version":{"major":1,"minor":1,"patch":3}},
///   "layer_keys":[{"layer":2,"partition":0}],
///   "nodes":[{"id":5692549928996306947,"layer":2,"partition":0,
///             "attributes":{"type":"ObjectNodeAttributes","position":[1,2,3],"name":"desk"}}],
///   "edges":[]}"#;
/// let g = ygg_dsg::parse_json(json, "inline.json")?;
/// assert_eq!(g.nodes[0].id, 5692549928996306947);
/// assert_eq!(g.nodes[0].symbol().to_string(), "O(3)");
/// assert_eq!(g.nodes[0].label.as_deref(), Some("desk"));
/// # Ok::<(), ygg_dsg::DsgImportError>(())
/// ```
pub fn parse_json(bytes: &[u8], source_name: &str) -> Result<DsgGraph, DsgImportError> {
    parse_json_with_progress(bytes, source_name, &mut |_| {})
}

/// [`parse_json`] with [`ImportOptions`]: with `lenient`, the faults of every
/// [`DropClass`] are dropped and listed in [`Imported::report`] instead of failing
/// (JSON nodes of unknown attribute types are skipped whole).
///
/// # Errors
/// As [`parse_json`], less the faults a lenient import drops.
///
/// # Examples
/// ```
/// use ygg_dsg::{DropClass, ImportOptions};
/// let json = br#"{"layer_ids":[2],
///   "nodes":[{"id":1,"layer":2,"attributes":{"type":"ObjectNodeAttributes","position":[0,0,0]}}],
///   "edges":[{"source":1,"target":2}]}"#;
/// let strict = ygg_dsg::parse_json(json, "dangling.json").unwrap_err();
/// assert!(strict.to_string().contains("--lenient"));
/// let lenient = ygg_dsg::parse_json_with(json, "dangling.json", ImportOptions::LENIENT)?;
/// assert_eq!(lenient.graph.nodes.len(), 1);
/// assert_eq!(lenient.report.count(DropClass::EdgeToAbsentNode), 1);
/// # Ok::<(), ygg_dsg::DsgImportError>(())
/// ```
pub fn parse_json_with(
    bytes: &[u8],
    source_name: &str,
    options: ImportOptions,
) -> Result<Imported, DsgImportError> {
    parse_json_impl(bytes, source_name, options, &mut |_| {})
}

/// [`parse_json`] that reports its phases ([`ImportPhase::Parse`], then
/// [`ImportPhase::Validate`], then [`ImportPhase::Done`]) to `progress`.
///
/// # Errors
/// As [`parse_json`].
pub fn parse_json_with_progress(
    bytes: &[u8],
    source_name: &str,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<DsgGraph, DsgImportError> {
    parse_json_impl(bytes, source_name, ImportOptions::STRICT, progress).map(|i| i.graph)
}

/// The general JSON import: options and progress.
pub(crate) fn parse_json_impl(
    bytes: &[u8],
    source_name: &str,
    options: ImportOptions,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Imported, DsgImportError> {
    let len = bytes.len() as u64;
    progress(ImportProgress::new(ImportPhase::Parse, 0, Some(len)));
    let raw: RawFile<'_> = match serde_json::from_slice(bytes) {
        Ok(raw) => raw,
        Err(e) => return Err(diag::diagnose(bytes, source_name, &e)),
    };
    progress(ImportProgress::new(ImportPhase::Parse, len, Some(len)));
    let imported = build_graph(raw, source_name, options, progress)?;
    progress(ImportProgress::new(ImportPhase::Done, len, Some(len)));
    Ok(imported)
}

/// Checks a parsed file and converts it to a [`DsgGraph`], reporting
/// [`ImportPhase::Validate`]: the step the JSON and the binary importers share, so
/// that both enforce one set of graph invariants.
pub(crate) fn build_graph(
    raw: RawFile<'_>,
    source_name: &str,
    options: ImportOptions,
    progress: &mut dyn FnMut(ImportProgress),
) -> Result<Imported, DsgImportError> {
    Builder::new(source_name, options, progress).build(raw)
}

/// One node record converted as [`build_graph`] converts each (strictly), for a body
/// whose other records are those of a graph already built; the node may only be in
/// `layer` (the layer its record had there). `None` for anything `build_graph` would
/// refuse or place elsewhere: the caller then builds the whole body, which reports it.
pub(crate) fn build_node_in_layer(
    raw: RawNode<'_>,
    layer: LayerKey,
    labelspaces: &BTreeMap<String, BTreeMap<u32, String>>,
    source_name: &str,
) -> Option<DsgNode> {
    let mut progress = |_| {};
    let builder = Builder::new(source_name, ImportOptions::STRICT, &mut progress);
    let declared = Declared::Keys(BTreeSet::from([layer]));
    builder.node(raw, false, &declared, labelspaces).ok()
}

struct Builder<'p> {
    file: String,
    lenient: bool,
    report: ImportReport,
    progress: &'p mut dyn FnMut(ImportProgress),
}

/// Which layers nodes may use.
enum Declared {
    /// v1.1 `layer_keys`: exactly these keys.
    Keys(BTreeSet<LayerKey>),
    /// `layer_ids`: these layer ids, any partition.
    Ids(BTreeSet<u32>),
}

impl Declared {
    fn allows(&self, key: LayerKey) -> bool {
        match self {
            Declared::Keys(k) => k.contains(&key),
            Declared::Ids(ids) => ids.contains(&key.layer),
        }
    }
}

impl<'p> Builder<'p> {
    fn new(
        file: &str,
        options: ImportOptions,
        progress: &'p mut dyn FnMut(ImportProgress),
    ) -> Self {
        Self {
            file: file.to_owned(),
            lenient: options.lenient,
            report: ImportReport::default(),
            progress,
        }
    }

    /// Drops the fault `e` (recording it) when lenient and tolerable; else returns it.
    fn tolerate(&mut self, e: DsgImportError) -> Result<(), DsgImportError> {
        self.report.tolerate(self.lenient, e)
    }

    fn build(mut self, raw: RawFile<'_>) -> Result<Imported, DsgImportError> {
        let version = match &raw.header {
            Some(h) => DsgVersion::new(h.version.major, h.version.minor, h.version.patch),
            None => DsgVersion::LEGACY,
        };
        if version.major != 1 {
            return Err(DsgImportError::UnsupportedVersion {
                file: self.file,
                version,
            });
        }
        let legacy = version.is_legacy();

        let declared = if let Some(keys) = &raw.layer_keys {
            Declared::Keys(
                keys.iter()
                    .map(|k| LayerKey::new(k.layer, k.partition))
                    .collect(),
            )
        } else if let Some(ids) = &raw.layer_ids {
            Declared::Ids(ids.iter().map(|k| k.layer).collect())
        } else {
            return Err(DsgImportError::MissingField {
                file: self.file,
                node: None,
                field: if legacy { "layer_ids" } else { "layer_keys" }.to_owned(),
            });
        };

        let labelspaces: BTreeMap<String, BTreeMap<u32, String>> = raw
            .metadata
            .and_then(|m| m.labelspaces)
            .map(|ls| {
                ls.into_iter()
                    .map(|(k, v)| (k, v.into_iter().collect()))
                    .collect()
            })
            .unwrap_or_default();

        let raw_nodes = raw.nodes.unwrap_or_default();
        let raw_edges = raw.edges.unwrap_or_default();
        let work = (raw_nodes.len() + raw_edges.len()) as u64;
        (self.progress)(ImportProgress::new(ImportPhase::Validate, 0, Some(work)));

        // ---- nodes
        let mut index: FxHashMap<u64, usize> = FxHashMap::default();
        index.reserve(raw_nodes.len());
        let mut nodes = Vec::with_capacity(raw_nodes.len());
        let mut used_keys = BTreeSet::new();
        // Ids of the nodes a lenient import dropped (unknown type or layer).
        let mut dropped_nodes: FxHashSet<u64> = FxHashSet::default();
        // Position in the file's `nodes` of each kept node.
        let mut file_position: Vec<usize> = Vec::with_capacity(raw_nodes.len());
        for (i, rn) in raw_nodes.into_iter().enumerate() {
            let id = rn.id;
            let node = match self.node(rn, legacy, &declared, &labelspaces) {
                Ok(node) => node,
                Err(e) => {
                    self.tolerate(e)?;
                    dropped_nodes.insert(id);
                    continue;
                }
            };
            if let Some(&first) = index.get(&node.id) {
                self.tolerate(DsgImportError::DuplicateNode {
                    file: self.file.clone(),
                    node: node.id,
                    first: file_position[first],
                    second: i,
                })?;
                continue;
            }
            index.insert(node.id, nodes.len());
            file_position.push(i);
            used_keys.insert(node.layer);
            nodes.push(node);
        }
        // A dropped id that another node uses is not absent.
        dropped_nodes.retain(|id| !index.contains_key(id));

        // ---- mesh
        let mesh = match raw.mesh {
            Some(m) => Some(self.mesh(m)?),
            None => None,
        };
        if let Some(m) = &mesh {
            let nv = m.points.len();
            for n in &mut nodes {
                if n.mesh_connections.iter().all(|&v| (v as usize) < nv) {
                    continue;
                }
                for (k, &v) in n.mesh_connections.iter().enumerate() {
                    if v as usize >= nv {
                        self.report.tolerate(
                            self.lenient,
                            DsgImportError::MeshConnectionOutOfRange {
                                file: self.file.clone(),
                                node: n.id,
                                index: k,
                                vertex: v,
                                vertex_count: nv,
                            },
                        )?;
                    }
                }
                n.mesh_connections.retain(|&v| (v as usize) < nv);
            }
        }

        // ---- edges
        let mut edges = Vec::new();
        let mut sibling_edges = Vec::new();
        let mut extra_parent_edges = Vec::new();
        let mut seen: FxHashSet<(u64, u64)> = FxHashSet::default();
        seen.reserve(raw_edges.len());
        for (e, re) in raw_edges.iter().enumerate() {
            let (s, t) = (re.source, re.target);
            if s == t {
                self.tolerate(DsgImportError::SelfEdge {
                    file: self.file.clone(),
                    edge: e,
                    node: s,
                })?;
                continue;
            }
            let (Some(&si), Some(&ti)) = (index.get(&s), index.get(&t)) else {
                let missing = if index.contains_key(&s) { t } else { s };
                if dropped_nodes.contains(&missing) {
                    let file = &self.file;
                    self.report.record(DropClass::EdgeToDroppedNode, || {
                        format!(
                            "{file}: edges[{e}] {} -> {}: node {} was dropped",
                            describe_id(s),
                            describe_id(t),
                            describe_id(missing)
                        )
                    });
                } else {
                    self.tolerate(DsgImportError::DanglingEdge {
                        file: self.file.clone(),
                        edge: e,
                        from: s,
                        to: t,
                        missing,
                    })?;
                }
                continue;
            };
            if !seen.insert((s.min(t), s.max(t))) {
                self.tolerate(DsgImportError::DuplicateEdge {
                    file: self.file.clone(),
                    edge: e,
                    from: s,
                    to: t,
                })?;
                continue;
            }
            let (sk, tk) = (nodes[si].layer, nodes[ti].layer);
            if sk == tk {
                let weight = re
                    .info
                    .as_ref()
                    .filter(|i| i.weighted.unwrap_or(false))
                    .map(|i| i.weight.0);
                if let Some(w) = weight
                    && !w.is_finite()
                {
                    return Err(DsgImportError::NonFinite {
                        file: self.file,
                        node: None,
                        field: format!("edges[{e}].info.weight"),
                        value: w as f32,
                    });
                }
                edges.push(DsgEdge {
                    source: s,
                    target: t,
                    weight,
                });
            } else if sk.layer == tk.layer {
                sibling_edges.push(DsgEdge {
                    source: s,
                    target: t,
                    weight: None,
                });
            } else {
                let (pi, ci) = if sk.is_parent_of(tk) {
                    (si, ti)
                } else {
                    (ti, si)
                };
                let parent = nodes[pi].id;
                let child = &mut nodes[ci];
                if child.parent.is_none() {
                    child.parent = Some(parent);
                } else {
                    extra_parent_edges.push(DsgParentEdge {
                        parent,
                        child: child.id,
                    });
                }
            }
        }
        (self.progress)(ImportProgress::new(ImportPhase::Validate, work, Some(work)));

        let layers = self.layers(&declared, &used_keys, raw.layer_names.as_ref(), legacy);
        Ok(Imported {
            graph: DsgGraph {
                source: self.file,
                version,
                layers,
                nodes,
                edges,
                sibling_edges,
                extra_parent_edges,
                mesh,
                labelspaces,
            },
            report: self.report,
        })
    }

    fn node(
        &self,
        rn: RawNode<'_>,
        legacy: bool,
        declared: &Declared,
        labelspaces: &BTreeMap<String, BTreeMap<u32, String>>,
    ) -> Result<DsgNode, DsgImportError> {
        let id = rn.id;
        let a = rn.attributes;
        let Some(kind) = NodeKind::from_attribute_type(&a.type_name) else {
            return Err(DsgImportError::UnknownNodeType {
                file: self.file.clone(),
                node: id,
                type_name: a.type_name.into_owned(),
            });
        };
        let partition = match (rn.partition, legacy) {
            (Some(p), _) => p,
            // Spark-DSG < 1.1: nodes with a node-level timestamp are agent poses,
            // partitioned by their prefix character.
            (None, true) => {
                if rn.timestamp.is_some() {
                    u32::from(NodeSymbol::from_id(id).prefix())
                } else {
                    0
                }
            }
            (None, false) => {
                return Err(DsgImportError::MissingField {
                    file: self.file.clone(),
                    node: Some(id),
                    field: "partition".to_owned(),
                });
            }
        };
        let layer = LayerKey::new(rn.layer, partition);
        if !declared.allows(layer) {
            return Err(DsgImportError::UnknownLayer {
                file: self.file.clone(),
                node: id,
                layer,
            });
        }
        let position = self.vec3(&a.position, Some(id), "attributes.position")?;
        let bbox = match &a.bounding_box {
            Some(b) => self.bbox(b, id)?,
            None => None,
        };
        let semantic_label = a.semantic_label.filter(|&l| l != u32::MAX);
        let name = a
            .name
            .filter(|n| !n.is_empty())
            .map(std::borrow::Cow::into_owned);
        let from_space = semantic_label.and_then(|l| {
            labelspaces
                .get(&format!("_l{}p{}", layer.layer, layer.partition))
                .and_then(|ls| ls.get(&l))
                .cloned()
        });
        let label = from_space.or_else(|| name.clone().filter(|n| !looks_like_symbol(n)));
        Ok(DsgNode {
            id,
            layer,
            kind,
            position,
            name,
            label,
            semantic_label,
            bbox,
            mesh_connections: a.mesh_connections.unwrap_or_default(),
            timestamp_ns: a.timestamp.or(rn.timestamp),
            parent: None,
        })
    }

    /// Converts to f32 and checks finiteness.
    fn vec3(
        &self,
        v: &[Num; 3],
        node: Option<u64>,
        field: &str,
    ) -> Result<[f32; 3], DsgImportError> {
        let mut out = [0f32; 3];
        for (k, (o, n)) in out.iter_mut().zip(v).enumerate() {
            let x = n.0 as f32;
            if !x.is_finite() {
                return Err(DsgImportError::NonFinite {
                    file: self.file.clone(),
                    node,
                    field: format!("{field}[{k}]"),
                    value: x,
                });
            }
            *o = x;
        }
        Ok(out)
    }

    fn bbox(&self, b: &RawBox<'_>, id: u64) -> Result<Option<DsgAabb>, DsgImportError> {
        let type_name = b.type_name.as_deref();
        if type_name == Some("INVALID") {
            return Ok(None);
        }
        let field = "attributes.bounding_box";
        let (min, max) = if let (Some(d), Some(c)) = (&b.dimensions, &b.center) {
            let d = self.vec3(d, Some(id), &format!("{field}.dimensions"))?;
            let c = self.vec3(c, Some(id), &format!("{field}.world_P_center"))?;
            let half = d.map(|x| x / 2.0);
            let ext = match &b.rotation {
                Some(q) => {
                    let q = [q.w.0, q.x.0, q.y.0, q.z.0];
                    if q.iter().any(|x| !x.is_finite()) {
                        return Err(DsgImportError::NonFinite {
                            file: self.file.clone(),
                            node: Some(id),
                            field: format!("{field}.world_R_center"),
                            value: f32::NAN,
                        });
                    }
                    rotated_extent(q, half)
                }
                None => half,
            };
            let mut min = [0f32; 3];
            let mut max = [0f32; 3];
            for k in 0..3 {
                min[k] = c[k] - ext[k];
                max[k] = c[k] + ext[k];
            }
            (min, max)
        } else if let (Some(lo), Some(hi)) = (&b.min, &b.max) {
            (
                self.vec3(lo, Some(id), &format!("{field}.min"))?,
                self.vec3(hi, Some(id), &format!("{field}.max"))?,
            )
        } else if type_name.is_none() {
            return Ok(None);
        } else {
            return Err(DsgImportError::MissingField {
                file: self.file.clone(),
                node: Some(id),
                field: format!("{field}.dimensions"),
            });
        };
        // An inverted box (negative dimensions) carries no usable bound.
        if (0..3).any(|k| min[k] > max[k]) {
            return Ok(None);
        }
        Ok(Some(DsgAabb { min, max }))
    }

    fn mesh(&self, m: RawMesh) -> Result<DsgMesh, DsgImportError> {
        let mut points = Vec::new();
        if let Some(p) = m.points {
            points.reserve_exact(p.len());
            for (i, v) in p.iter().enumerate() {
                points.push(self.mesh_point([v[0].0, v[1].0, v[2].0], i, "mesh.points")?);
            }
        } else if let Some(vs) = m.vertices {
            points.reserve_exact(vs.len());
            for (i, v) in vs.iter().enumerate() {
                points.push(self.mesh_point([v.x.0, v.y.0, v.z.0], i, "mesh.vertices")?);
            }
        }
        let nv = points.len();
        let faces = m.faces.unwrap_or_default();
        for (f, face) in faces.iter().enumerate() {
            if let Some(&v) = face.iter().find(|&&v| v as usize >= nv) {
                return Err(DsgImportError::FaceOutOfRange {
                    file: self.file.clone(),
                    face: f,
                    vertex: v,
                    vertex_count: nv,
                });
            }
        }
        let labels = m.labels.filter(|l| !l.is_empty());
        if let Some(l) = &labels
            && l.len() != nv
        {
            return Err(DsgImportError::MeshLabelCount {
                file: self.file.clone(),
                labels: l.len(),
                vertex_count: nv,
            });
        }
        Ok(DsgMesh {
            points,
            faces,
            labels,
        })
    }

    #[inline]
    fn mesh_point(&self, v: [f64; 3], i: usize, field: &str) -> Result<[f32; 3], DsgImportError> {
        let p = v.map(|x| x as f32);
        if let Some(k) = p.iter().position(|x| !x.is_finite()) {
            return Err(DsgImportError::NonFinite {
                file: self.file.clone(),
                node: None,
                field: format!("{field}[{i}][{k}]"),
                value: p[k],
            });
        }
        Ok(p)
    }

    fn layers(
        &self,
        declared: &Declared,
        used: &BTreeSet<LayerKey>,
        names: Option<&BTreeMap<String, crate::raw::RawLayerRef>>,
        legacy: bool,
    ) -> Vec<DsgLayer> {
        let mut keys: BTreeSet<LayerKey> = used.clone();
        match declared {
            Declared::Keys(k) => keys.extend(k.iter().copied()),
            Declared::Ids(ids) => keys.extend(ids.iter().map(|&l| LayerKey::new(l, 0))),
        }
        let mut by_key: BTreeMap<LayerKey, Vec<String>> = BTreeMap::new();
        match names {
            Some(names) => {
                for (name, r) in names {
                    by_key
                        .entry(LayerKey::new(r.layer, r.partition))
                        .or_default()
                        .push(name.clone());
                }
            }
            None if legacy => {
                for (name, layer) in [
                    ("OBJECTS", 2),
                    ("AGENTS", 2),
                    ("PLACES", 3),
                    ("ROOMS", 4),
                    ("BUILDINGS", 5),
                ] {
                    by_key
                        .entry(LayerKey::new(layer, 0))
                        .or_default()
                        .push(name.to_owned());
                }
            }
            None => {}
        }
        let mut taken = BTreeSet::new();
        let mut out = Vec::with_capacity(keys.len());
        for key in keys {
            let mut aliases = by_key.remove(&key).unwrap_or_default();
            aliases.sort();
            let default = DsgLayer::default_name(key);
            let mut name = if aliases.is_empty() || aliases.contains(&default) {
                default
            } else {
                aliases[0].clone()
            };
            if taken.contains(&name) {
                name = format!("{name}_{}_{}", key.layer, key.partition);
            }
            taken.insert(name.clone());
            out.push(DsgLayer { key, name, aliases });
        }
        out
    }
}

/// Half extents of the axis-aligned box around a box with half extents `half`
/// rotated by the quaternion `q = [w, x, y, z]` (normalised here).
fn rotated_extent(q: [f64; 4], half: [f32; 3]) -> [f32; 3] {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n <= 1e-12 {
        return half;
    }
    let [w, x, y, z] = q.map(|c| c / n);
    if (w.abs() - 1.0).abs() < 1e-9 {
        return half;
    }
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let mut e = [0f32; 3];
    for (i, row) in r.iter().enumerate() {
        let s: f64 = row
            .iter()
            .zip(half)
            .map(|(rij, h)| rij.abs() * f64::from(h))
            .sum();
        e[i] = s as f32;
    }
    e
}
