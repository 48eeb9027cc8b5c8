//! Typed mirror of the Spark-DSG JSON layout (only the fields the importer uses;
//! serde skips the others without building values).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;

use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};

/// The whole file.
#[derive(Deserialize)]
#[serde(expecting = "a Spark-DSG JSON object")]
pub(super) struct RawFile<'a> {
    #[serde(rename = "SPARK_DSG_header", default)]
    pub header: Option<RawHeader>,
    #[serde(default)]
    pub layer_keys: Option<Vec<RawLayerRef>>,
    #[serde(default)]
    pub layer_ids: Option<Vec<RawLayerRef>>,
    #[serde(default)]
    pub layer_names: Option<BTreeMap<String, RawLayerRef>>,
    #[serde(default, borrow)]
    pub nodes: Option<Vec<RawNode<'a>>>,
    #[serde(default)]
    pub edges: Option<Vec<RawEdge>>,
    #[serde(default)]
    pub mesh: Option<RawMesh>,
    #[serde(default)]
    pub metadata: Option<RawMetadata>,
}

#[derive(Deserialize)]
pub(super) struct RawHeader {
    pub version: RawVersion,
}

#[derive(Deserialize)]
pub(super) struct RawVersion {
    pub major: u32,
    pub minor: u32,
    pub patch: u32,
}

/// A layer given either as a bare layer id (`2`) or as `{"layer":2,"partition":0}`.
#[derive(Clone, Copy)]
pub(super) struct RawLayerRef {
    pub layer: u32,
    pub partition: u32,
}

impl<'de> Deserialize<'de> for RawLayerRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawLayerRef;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a layer id or {\"layer\", \"partition\"}")
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawLayerRef, E> {
                let layer = u32::try_from(v)
                    .map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))?;
                Ok(RawLayerRef {
                    layer,
                    partition: 0,
                })
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawLayerRef, E> {
                match u64::try_from(v) {
                    Ok(v) => self.visit_u64(v),
                    Err(_) => Err(E::invalid_value(de::Unexpected::Signed(v), &self)),
                }
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawLayerRef, A::Error> {
                let mut layer = None;
                let mut partition = None;
                while let Some(key) = map.next_key::<Cow<'de, str>>()? {
                    match key.as_ref() {
                        "layer" => layer = Some(map.next_value::<u32>()?),
                        "partition" => partition = Some(map.next_value::<u32>()?),
                        _ => {
                            map.next_value::<de::IgnoredAny>()?;
                        }
                    }
                }
                Ok(RawLayerRef {
                    layer: layer.ok_or_else(|| de::Error::missing_field("layer"))?,
                    partition: partition.unwrap_or(0),
                })
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
pub(super) struct RawNode<'a> {
    pub id: u64,
    pub layer: u32,
    #[serde(default)]
    pub partition: Option<u32>,
    /// Legacy agents carry the timestamp at node level.
    #[serde(default)]
    pub timestamp: Option<u64>,
    #[serde(borrow)]
    pub attributes: RawAttrs<'a>,
}

#[derive(Deserialize)]
pub(super) struct RawAttrs<'a> {
    #[serde(rename = "type", borrow)]
    pub type_name: Cow<'a, str>,
    pub position: [Num; 3],
    #[serde(default, borrow)]
    pub name: Option<Cow<'a, str>>,
    #[serde(default)]
    pub semantic_label: Option<u32>,
    #[serde(default, borrow)]
    pub bounding_box: Option<RawBox<'a>>,
    #[serde(default)]
    pub mesh_connections: Option<Vec<u32>>,
    #[serde(default)]
    pub timestamp: Option<u64>,
}

#[derive(Deserialize)]
pub(super) struct RawBox<'a> {
    #[serde(rename = "type", default, borrow)]
    pub type_name: Option<Cow<'a, str>>,
    #[serde(default)]
    pub dimensions: Option<[Num; 3]>,
    #[serde(rename = "world_P_center", default)]
    pub center: Option<[Num; 3]>,
    #[serde(rename = "world_R_center", default)]
    pub rotation: Option<RawQuat>,
    #[serde(default)]
    pub min: Option<[Num; 3]>,
    #[serde(default)]
    pub max: Option<[Num; 3]>,
}

#[derive(Deserialize)]
pub(super) struct RawQuat {
    pub w: Num,
    pub x: Num,
    pub y: Num,
    pub z: Num,
}

#[derive(Deserialize)]
pub(super) struct RawEdge {
    pub source: u64,
    pub target: u64,
    #[serde(default)]
    pub info: Option<RawEdgeInfo>,
}

#[derive(Deserialize)]
pub(super) struct RawEdgeInfo {
    /// `null` (nlohmann's NaN) and a missing weight both read as NaN.
    #[serde(default = "Num::nan")]
    pub weight: Num,
    #[serde(default)]
    pub weighted: Option<bool>,
}

#[derive(Deserialize)]
pub(super) struct RawMesh {
    #[serde(default)]
    pub points: Option<Vec<[Num; 3]>>,
    #[serde(default)]
    pub faces: Option<Vec<[u32; 3]>>,
    #[serde(default)]
    pub labels: Option<Vec<u32>>,
    /// Legacy meshes: `[{x,y,z,r,g,b}]`.
    #[serde(default)]
    pub vertices: Option<Vec<RawLegacyVertex>>,
}

#[derive(Deserialize)]
pub(super) struct RawLegacyVertex {
    pub x: Num,
    pub y: Num,
    pub z: Num,
}

#[derive(Deserialize)]
pub(super) struct RawMetadata {
    #[serde(default)]
    pub labelspaces: Option<BTreeMap<String, Vec<(u32, String)>>>,
}

/// A JSON number, or `null` (nlohmann writes NaN and infinities as `null`), read as
/// f64; `null` becomes NaN so the finiteness checks can name the field.
#[derive(Clone, Copy, Debug)]
pub(super) struct Num(pub f64);

impl Num {
    fn nan() -> Self {
        Num(f64::NAN)
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Num;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num, E> {
                Ok(Num(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num, E> {
                Ok(Num(v as f64))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num, E> {
                Ok(Num(v as f64))
            }
            fn visit_unit<E: de::Error>(self) -> Result<Num, E> {
                Ok(Num(f64::NAN))
            }
            fn visit_none<E: de::Error>(self) -> Result<Num, E> {
                Ok(Num(f64::NAN))
            }
        }
        d.deserialize_any(V)
    }
}
