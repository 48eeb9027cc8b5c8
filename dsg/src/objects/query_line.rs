//! [`ObjectQuery`]: one query of the contract as a JSON line, and [`Objects::answer`].

use super::{ObjectQueryError, Objects};
use ygg_store::{NodeId, Point, SceneView};

/// One query of the contract, as `ygg query` reads it from a JSON line
/// (`{"op":"nearest_object","point":[x,y,z]}`, ...): see [`ObjectQuery::from_json`].
/// Serializes to that same form; deserializes from it with serde (any self-describing
/// format; [`ObjectQuery::from_value`] adds the checks that word the errors for a JSON
/// user).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObjectQuery {
    /// [`Objects::nearest_object`].
    NearestObject {
        /// The query point.
        #[serde(deserialize_with = "field::point")]
        point: Point,
    },
    /// [`Objects::objects_within`].
    ObjectsWithin {
        /// The centre.
        #[serde(deserialize_with = "field::point")]
        point: Point,
        /// The radius, metres (inclusive).
        #[serde(deserialize_with = "field::radius")]
        radius: f32,
    },
    /// [`Objects::visible_objects`].
    VisibleObjects {
        /// The apex of the view.
        #[serde(deserialize_with = "field::eye")]
        eye: Point,
        /// The viewing direction (any finite non-zero vector).
        #[serde(deserialize_with = "field::dir")]
        dir: Point,
        /// Half of the opening angle, degrees, in `[0, 180]`.
        #[serde(deserialize_with = "field::half_angle_deg")]
        half_angle_deg: f32,
        /// How far the view reaches, metres.
        #[serde(deserialize_with = "field::range")]
        range: f32,
    },
    /// [`Objects::objects_with_label`].
    ObjectsWithLabel {
        /// The label.
        #[serde(deserialize_with = "field::label")]
        label: String,
    },
}

impl ObjectQuery {
    /// The operations, as `"op"` names them.
    pub const OPS: [&'static str; 4] = [
        "nearest_object",
        "objects_within",
        "visible_objects",
        "objects_with_label",
    ];

    /// Reads a query from one JSON line.
    ///
    /// Numbers are read as `f64` and rounded to `f32`; one too large for `f32` is refused.
    ///
    /// # Errors
    /// A message naming what is wrong: malformed JSON, a missing or unknown `op`, a
    /// missing, unknown or mistyped field (`field "point": expected an array of 3
    /// numbers, got [1,2]`).
    ///
    /// # Examples
    /// ```
    /// # use ygg_dsg::objects::ObjectQuery;
    /// let q = ObjectQuery::from_json(r#"{"op":"objects_within","point":[1,2,0.5],"radius":2}"#);
    /// assert_eq!(q, Ok(ObjectQuery::ObjectsWithin { point: [1.0, 2.0, 0.5], radius: 2.0 }));
    /// let e = ObjectQuery::from_json(r#"{"op":"objects_within","point":[1,2],"radius":2}"#);
    /// assert!(e.unwrap_err().contains("field \"point\""));
    /// ```
    pub fn from_json(line: &str) -> Result<Self, String> {
        let v: serde_json::Value =
            serde_json::from_str(line).map_err(|e| format!("malformed JSON: {e}"))?;
        Self::from_value(&v)
    }

    /// Reads a query from a parsed JSON value (as [`ObjectQuery::from_json`]).
    ///
    /// # Errors
    /// As [`ObjectQuery::from_json`].
    pub fn from_value(v: &serde_json::Value) -> Result<Self, String> {
        use serde::Deserialize as _;
        // Serde's internally tagged form also takes `[op, fields...]` arrays and words a
        // missing or mistyped tag for Rust readers; these two checks word them for JSON.
        let Some(obj) = v.as_object() else {
            return Err(format!(
                "expected a JSON object with an \"op\" ({}), got {}",
                Self::OPS.join(", "),
                brief(v)
            ));
        };
        match obj.get("op") {
            Some(serde_json::Value::String(_)) => {}
            Some(other) => return Err(format!("\"op\" must be a string, got {}", brief(other))),
            None => {
                return Err(format!(
                    "missing field \"op\" (one of {})",
                    Self::OPS.join(", ")
                ));
            }
        }
        // Serde quotes names in backticks (`missing field `label``) and calls an op a
        // variant; JSON users read double quotes and the field's name.
        ObjectQuery::deserialize(v).map_err(|e| {
            e.to_string()
                .replace('`', "\"")
                .replace("unknown variant", "unknown op")
        })
    }
}

/// The field readers of [`ObjectQuery`]'s `#[serde(deserialize_with)]`: each reads its
/// field as a JSON value and names the field in its message.
mod field {
    use serde::de::{Deserialize, Deserializer, Error};
    use serde_json::Value;
    use ygg_store::Point;

    /// A reader `$field` of a `$ty` field, checked by `$read`.
    macro_rules! reader {
        ($($field:ident: $ty:ty = $read:ident;)*) => {$(
            pub(super) fn $field<'de, D: Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                $read(stringify!($field), &Value::deserialize(d)?).map_err(D::Error::custom)
            }
        )*};
    }

    reader! {
        point: Point = point_in;
        eye: Point = point_in;
        dir: Point = point_in;
        radius: f32 = number_in;
        half_angle_deg: f32 = number_in;
        range: f32 = number_in;
        label: String = string_in;
    }

    fn to_f32(name: &str, x: f64) -> Result<f32, String> {
        let y = x as f32;
        if y.is_finite() {
            Ok(y)
        } else {
            Err(format!("field {name:?}: {x:?} is not a finite f32"))
        }
    }

    fn number_in(name: &str, v: &Value) -> Result<f32, String> {
        let x = v
            .as_f64()
            .ok_or_else(|| format!("field {name:?}: expected a number, got {}", super::brief(v)))?;
        to_f32(name, x)
    }

    fn point_in(name: &str, v: &Value) -> Result<Point, String> {
        let xyz: Option<Vec<f64>> = v
            .as_array()
            .filter(|a| a.len() == 3)
            .and_then(|a| a.iter().map(Value::as_f64).collect());
        let xyz = xyz.ok_or_else(|| {
            format!(
                "field {name:?}: expected an array of 3 numbers, got {}",
                super::brief(v)
            )
        })?;
        Ok([
            to_f32(name, xyz[0])?,
            to_f32(name, xyz[1])?,
            to_f32(name, xyz[2])?,
        ])
    }

    fn string_in(name: &str, v: &Value) -> Result<String, String> {
        v.as_str()
            .map(str::to_owned)
            .ok_or_else(|| format!("field {name:?}: expected a string, got {}", super::brief(v)))
    }
}

/// A JSON value for a message, cut to a readable length.
fn brief(v: &serde_json::Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(60) {
        Some((at, _)) => format!("{}...", &s[..at]),
        None => s,
    }
}

impl<V: SceneView> Objects<'_, V> {
    /// Answers one query of the contract: ids ascending (at most one for
    /// [`ObjectQuery::NearestObject`]).
    ///
    /// # Errors
    /// As the query's method.
    pub fn answer(&self, q: &ObjectQuery) -> Result<Vec<NodeId>, ObjectQueryError> {
        match q {
            ObjectQuery::NearestObject { point } => {
                Ok(self.nearest_object(*point)?.into_iter().collect())
            }
            ObjectQuery::ObjectsWithin { point, radius } => self.objects_within(*point, *radius),
            ObjectQuery::VisibleObjects {
                eye,
                dir,
                half_angle_deg,
                range,
            } => self.visible_objects(*eye, *dir, *half_angle_deg, *range),
            ObjectQuery::ObjectsWithLabel { label } => Ok(self.objects_with_label(label)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_parse_from_json_lines() {
        let q = ObjectQuery::from_json(r#"{"op":"nearest_object","point":[1,2.5,-3]}"#);
        assert_eq!(
            q,
            Ok(ObjectQuery::NearestObject {
                point: [1.0, 2.5, -3.0]
            })
        );
        let q = ObjectQuery::from_json(
            r#"{"op":"visible_objects","eye":[0,0,1],"dir":[1,0,0],"half_angle_deg":30,"range":4}"#,
        );
        assert!(matches!(q, Ok(ObjectQuery::VisibleObjects { .. })));
        for (bad, says) in [
            (
                r#"{"op":"nearest_object","point":[1,2]}"#,
                "field \"point\"",
            ),
            (
                r#"{"op":"nearest_object","point":[1,2,3],"radius":1}"#,
                "\"radius\"",
            ),
            (r#"{"op":"teleport"}"#, "teleport"),
            (r#"{"point":[1,2,3]}"#, "missing field \"op\""),
            (r#"{"op":7}"#, "\"op\" must be a string"),
            (
                r#"{"op":"objects_with_label","label":7}"#,
                "field \"label\"",
            ),
            (r#"{"op":"objects_with_label"}"#, "missing field \"label\""),
            (
                r#"{"op":"objects_within","point":[0,0,0],"radius":"far"}"#,
                "\"far\"",
            ),
            (r#"[1,2,3]"#, "expected a JSON object"),
            (r#"{"op":"nearest_object""#, "malformed JSON"),
        ] {
            let e = ObjectQuery::from_json(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
        // Serializing gives the same line back.
        let q = ObjectQuery::ObjectsWithLabel {
            label: "light".into(),
        };
        let line = serde_json::to_string(&q).unwrap();
        assert_eq!(line, r#"{"op":"objects_with_label","label":"light"}"#);
        assert_eq!(ObjectQuery::from_json(&line), Ok(q));
    }
}
