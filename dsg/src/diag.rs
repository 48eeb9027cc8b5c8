//! Turning a serde_json error of the fast typed parse into a [`DsgImportError`] that
//! names the node and field.
//!
//! The fast parse keeps no context: a type error only carries a line and column.
//! Only on that error path, the document is parsed a second time with the node and
//! edge lists as `serde_json::Value`s (small next to the mesh) and the mesh arrays
//! through visitors that count their position, and each piece is checked again on
//! its own to find the culprit.

use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::{self, DeserializeOwned, Deserializer, SeqAccess, Visitor};
use serde_json::Value;

use super::error::DsgImportError;
use super::raw::{
    Num, RawBox, RawEdge, RawEdgeInfo, RawHeader, RawLayerRef, RawLegacyVertex, RawMetadata,
    RawNode, RawQuat,
};

/// Separates a field path from the message inside located error strings.
const SEP: char = '\u{1f}';

pub(super) fn diagnose(bytes: &[u8], file: &str, err: &serde_json::Error) -> DsgImportError {
    let (line, column) = (err.line(), err.column());
    let message = strip_position(&err.to_string());
    if !err.is_data() {
        return DsgImportError::Syntax {
            file: file.to_owned(),
            line,
            column,
            message,
        };
    }
    let loc = locate(bytes).unwrap_or(Loc {
        node: None,
        field: "(document)".to_owned(),
        message,
    });
    DsgImportError::InvalidField {
        file: file.to_owned(),
        node: loc.node,
        field: loc.field,
        message: loc.message,
        line,
        column,
    }
}

struct Loc {
    node: Option<u64>,
    field: String,
    message: String,
}

impl Loc {
    fn new(node: Option<u64>, field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            node,
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Removes serde_json's trailing ` at line L column C` (possibly repeated).
fn strip_position(s: &str) -> String {
    let mut s = s;
    while let Some(at) = s.rfind(" at line ") {
        let tail = &s[at + " at line ".len()..];
        let mut parts = tail.split(' ');
        let ok = matches!(
            (parts.next(), parts.next(), parts.next(), parts.next()),
            (Some(l), Some("column"), Some(c), None)
                if l.bytes().all(|b| b.is_ascii_digit()) && c.bytes().all(|b| b.is_ascii_digit())
        );
        if !ok {
            break;
        }
        s = &s[..at];
    }
    s.to_owned()
}

#[derive(Deserialize)]
#[serde(expecting = "a Spark-DSG JSON object")]
struct DiagTop {
    #[serde(rename = "SPARK_DSG_header", default)]
    header: Option<Value>,
    #[serde(default)]
    layer_keys: Option<Value>,
    #[serde(default)]
    layer_ids: Option<Value>,
    #[serde(default)]
    layer_names: Option<Value>,
    #[serde(default)]
    metadata: Option<Value>,
    #[serde(default)]
    nodes: Option<Value>,
    #[serde(default)]
    edges: Option<Value>,
    #[serde(default, deserialize_with = "de_mesh")]
    #[allow(dead_code, reason = "only checked")]
    mesh: (),
}

#[derive(Deserialize)]
#[serde(expecting = "a mesh object")]
struct DiagMesh {
    #[serde(default, deserialize_with = "de_points")]
    #[allow(dead_code, reason = "only checked")]
    points: (),
    #[serde(default, deserialize_with = "de_faces")]
    #[allow(dead_code, reason = "only checked")]
    faces: (),
    #[serde(default, deserialize_with = "de_labels")]
    #[allow(dead_code, reason = "only checked")]
    labels: (),
    #[serde(default, deserialize_with = "de_vertices")]
    #[allow(dead_code, reason = "only checked")]
    vertices: (),
}

fn de_mesh<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    Option::<DiagMesh>::deserialize(d).map(drop).map_err(|e| {
        let m = strip_position(&e.to_string());
        if m.contains(SEP) {
            de::Error::custom(m)
        } else {
            de::Error::custom(format!("mesh{SEP}{m}"))
        }
    })
}

fn de_points<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    d.deserialize_option(Located::<[Num; 3]>::new("mesh.points"))
}
fn de_faces<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    d.deserialize_option(Located::<[u32; 3]>::new("mesh.faces"))
}
fn de_labels<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    d.deserialize_option(Located::<u32>::new("mesh.labels"))
}
fn de_vertices<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
    d.deserialize_option(Located::<RawLegacyVertex>::new("mesh.vertices"))
}

/// Checks an optional array element by element, naming the first bad index.
struct Located<T> {
    path: &'static str,
    _t: PhantomData<T>,
}

impl<T> Located<T> {
    fn new(path: &'static str) -> Self {
        Self {
            path,
            _t: PhantomData,
        }
    }
}

impl<'de, T: Deserialize<'de>> Visitor<'de> for Located<T> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array ({})", self.path)
    }
    fn visit_none<E: de::Error>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        let path = self.path;
        d.deserialize_seq(self).map_err(|e| {
            let m = strip_position(&e.to_string());
            if m.contains(SEP) {
                de::Error::custom(m)
            } else {
                de::Error::custom(format!("{path}{SEP}{m}"))
            }
        })
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut i = 0usize;
        loop {
            match seq.next_element::<T>() {
                Ok(Some(_)) => i += 1,
                Ok(None) => return Ok(()),
                Err(e) => {
                    let m = strip_position(&e.to_string());
                    return Err(de::Error::custom(format!("{}[{i}]{SEP}{m}", self.path)));
                }
            }
        }
    }
}

/// Checks one JSON value against the type the fast parse expects.
type Check = fn(&Value) -> Result<(), String>;

fn check<'a, T: Deserialize<'a>>(v: &'a Value) -> Result<(), String> {
    T::deserialize(v).map(drop).map_err(|e| e.to_string())
}

fn check_owned<T: DeserializeOwned>(v: &Value) -> Result<(), String> {
    T::deserialize(v).map(drop).map_err(|e| e.to_string())
}

fn missing_field(msg: &str) -> Option<&str> {
    msg.strip_prefix("missing field `")?.strip_suffix('`')
}

fn locate(bytes: &[u8]) -> Option<Loc> {
    let top: DiagTop = match serde_json::from_slice(bytes) {
        Ok(t) => t,
        Err(e) => {
            let m = strip_position(&e.to_string());
            return Some(match m.split_once(SEP) {
                Some((path, msg)) => Loc::new(None, path, msg),
                None => Loc::new(None, "(document)", m),
            });
        }
    };
    let sections: [(&str, &Option<Value>, Check); 5] = [
        ("SPARK_DSG_header", &top.header, |v| {
            check_owned::<Option<RawHeader>>(v)
        }),
        ("layer_keys", &top.layer_keys, |v| {
            check_owned::<Option<Vec<RawLayerRef>>>(v)
        }),
        ("layer_ids", &top.layer_ids, |v| {
            check_owned::<Option<Vec<RawLayerRef>>>(v)
        }),
        ("layer_names", &top.layer_names, |v| {
            check_owned::<Option<std::collections::BTreeMap<String, RawLayerRef>>>(v)
        }),
        ("metadata", &top.metadata, |v| {
            check_owned::<Option<RawMetadata>>(v)
        }),
    ];
    for (name, v, f) in sections {
        if let Some(v) = v
            && let Err(m) = f(v)
        {
            return Some(Loc::new(None, name, m));
        }
    }
    if let Some(nodes) = top.nodes.as_ref().filter(|v| !v.is_null()) {
        let Some(list) = nodes.as_array() else {
            return Some(Loc::new(None, "nodes", "expected an array"));
        };
        for (i, v) in list.iter().enumerate() {
            if let Some(loc) = check_node(i, v) {
                return Some(loc);
            }
        }
    }
    if let Some(edges) = top.edges.as_ref().filter(|v| !v.is_null()) {
        let Some(list) = edges.as_array() else {
            return Some(Loc::new(None, "edges", "expected an array"));
        };
        for (i, v) in list.iter().enumerate() {
            if let Some(loc) = check_edge(i, v) {
                return Some(loc);
            }
        }
    }
    None
}

fn check_edge(i: usize, v: &Value) -> Option<Loc> {
    let err = check_owned::<RawEdge>(v).err()?;
    let base = format!("edges[{i}]");
    let Some(obj) = v.as_object() else {
        return Some(Loc::new(None, base, err));
    };
    if let Some(f) = missing_field(&err) {
        return Some(Loc::new(None, format!("{base}.{f}"), err));
    }
    for (key, val) in obj {
        let r = match key.as_str() {
            "source" | "target" => check::<u64>(val),
            "info" => check_owned::<Option<RawEdgeInfo>>(val),
            _ => Ok(()),
        };
        if let Err(m) = r {
            return Some(Loc::new(None, format!("{base}.{key}"), m));
        }
    }
    Some(Loc::new(None, base, err))
}

fn check_node(i: usize, v: &Value) -> Option<Loc> {
    let err = check::<RawNode<'_>>(v).err()?;
    let node = v.get("id").and_then(Value::as_u64);
    let base = format!("nodes[{i}]");
    let Some(obj) = v.as_object() else {
        return Some(Loc::new(node, base, err));
    };
    for (key, val) in obj {
        let r = match key.as_str() {
            "id" => check::<u64>(val),
            "layer" => check::<u32>(val),
            "partition" => check::<Option<u32>>(val),
            "timestamp" => check::<Option<u64>>(val),
            _ => Ok(()),
        };
        if let Err(m) = r {
            return Some(Loc::new(node, format!("{base}.{key}"), m));
        }
    }
    let Some(attrs) = obj.get("attributes") else {
        return Some(Loc::new(node, base, err));
    };
    let base = format!("{base}.attributes");
    let Some(aobj) = attrs.as_object() else {
        return Some(Loc::new(node, base, err));
    };
    for (key, val) in aobj {
        let field = format!("{base}.{key}");
        let r = match key.as_str() {
            "type" => check::<std::borrow::Cow<'_, str>>(val),
            "position" => match return_first_bad::<Num>(val, 3) {
                Some((j, m)) => Err(format!("[{j}]{SEP}{m}")),
                None => check::<[Num; 3]>(val),
            },
            "name" => check::<Option<std::borrow::Cow<'_, str>>>(val),
            "semantic_label" => check::<Option<u32>>(val),
            "timestamp" => check::<Option<u64>>(val),
            "mesh_connections" => match return_first_bad::<u32>(val, usize::MAX) {
                Some((j, m)) => Err(format!("[{j}]{SEP}{m}")),
                None => check::<Option<Vec<u32>>>(val),
            },
            "bounding_box" => match check::<Option<RawBox<'_>>>(val) {
                Ok(()) => Ok(()),
                Err(m) => {
                    return Some(locate_box(node, &field, val, m));
                }
            },
            _ => Ok(()),
        };
        if let Err(m) = r {
            return Some(match m.split_once(SEP) {
                Some((idx, msg)) => Loc::new(node, format!("{field}{idx}"), msg),
                None => Loc::new(node, field, m),
            });
        }
    }
    if let Some(f) = missing_field(&err) {
        let field = if obj.contains_key(f) || aobj.contains_key(f) {
            base
        } else if matches!(f, "id" | "layer" | "attributes") {
            format!("nodes[{i}].{f}")
        } else {
            format!("{base}.{f}")
        };
        return Some(Loc::new(node, field, err));
    }
    Some(Loc::new(node, base, err))
}

/// For an array value, the first element (below `limit`) that is not a `T`.
fn return_first_bad<T: DeserializeOwned>(v: &Value, limit: usize) -> Option<(usize, String)> {
    v.as_array()?
        .iter()
        .take(limit)
        .enumerate()
        .find_map(|(j, e)| check_owned::<T>(e).err().map(|m| (j, m)))
}

fn locate_box(node: Option<u64>, field: &str, val: &Value, err: String) -> Loc {
    if let Some(obj) = val.as_object() {
        for (key, v) in obj {
            let r = match key.as_str() {
                "type" => check::<Option<std::borrow::Cow<'_, str>>>(v),
                "dimensions" | "world_P_center" | "min" | "max" => {
                    match return_first_bad::<Num>(v, 3) {
                        Some((j, m)) => {
                            return Loc::new(node, format!("{field}.{key}[{j}]"), m);
                        }
                        None => check::<Option<[Num; 3]>>(v),
                    }
                }
                "world_R_center" => check::<Option<RawQuat>>(v),
                _ => Ok(()),
            };
            if let Err(m) = r {
                return Loc::new(node, format!("{field}.{key}"), m);
            }
        }
    }
    Loc::new(node, field, err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strip_position_removes_suffixes() {
        assert_eq!(strip_position("bad at line 1 column 2"), "bad");
        assert_eq!(
            strip_position("bad at line 1 column 2 at line 3 column 4"),
            "bad"
        );
        assert_eq!(strip_position("at line x"), "at line x");
    }
}
