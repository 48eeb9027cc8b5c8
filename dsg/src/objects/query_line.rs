//! [`ObjectQuery`]: one query of the contract as a JSON line, and [`Objects::answer`].

use super::{ObjectQueryError, Objects};
use ygg_store::{NodeId, Point, SceneView};

/// One query of the contract, as `ygg query` reads it from a JSON line
/// (`{"op":"nearest_object","point":[x,y,z]}`, ...): see [`ObjectQuery::from_json`].
/// Serializes to that same form.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum ObjectQuery {
    /// [`Objects::nearest_object`].
    NearestObject {
        /// The query point.
        point: Point,
    },
    /// [`Objects::objects_within`].
    ObjectsWithin {
        /// The centre.
        point: Point,
        /// The radius, metres (inclusive).
        radius: f32,
    },
    /// [`Objects::visible_objects`].
    VisibleObjects {
        /// The apex of the view.
        eye: Point,
        /// The viewing direction (any finite non-zero vector).
        dir: Point,
        /// Half of the opening angle, degrees, in `[0, 180]`.
        half_angle_deg: f32,
        /// How far the view reaches, metres.
        range: f32,
    },
    /// [`Objects::objects_with_label`].
    ObjectsWithLabel {
        /// The label.
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
        use serde_json::Value;
        let ops = || Self::OPS.join(", ");
        let Some(obj) = v.as_object() else {
            return Err(format!(
                "expected a JSON object with an \"op\" ({}), got {}",
                ops(),
                brief(v)
            ));
        };
        let op = match obj.get("op") {
            Some(Value::String(op)) => op.as_str(),
            Some(other) => return Err(format!("\"op\" must be a string, got {}", brief(other))),
            None => return Err(format!("missing field \"op\" (one of {})", ops())),
        };
        let fields: &[&str] = match op {
            "nearest_object" => &["point"],
            "objects_within" => &["point", "radius"],
            "visible_objects" => &["eye", "dir", "half_angle_deg", "range"],
            "objects_with_label" => &["label"],
            _ => return Err(format!("unknown op {op:?} (expected one of {})", ops())),
        };
        if let Some(k) = obj
            .keys()
            .find(|k| *k != "op" && !fields.contains(&k.as_str()))
        {
            return Err(format!(
                "unknown field {k:?} for op {op} (it takes {})",
                fields.join(", ")
            ));
        }
        let get = |name: &str| {
            obj.get(name)
                .ok_or_else(|| format!("missing field {name:?} for op {op}"))
        };
        let to_f32 = |name: &str, x: f64| -> Result<f32, String> {
            let y = x as f32;
            if y.is_finite() {
                Ok(y)
            } else {
                Err(format!("field {name:?}: {x:?} is not a finite f32"))
            }
        };
        let number = |name: &str| -> Result<f32, String> {
            let v = get(name)?;
            let x = v
                .as_f64()
                .ok_or_else(|| format!("field {name:?}: expected a number, got {}", brief(v)))?;
            to_f32(name, x)
        };
        let point = |name: &str| -> Result<Point, String> {
            let v = get(name)?;
            let xyz: Option<Vec<f64>> = v
                .as_array()
                .filter(|a| a.len() == 3)
                .and_then(|a| a.iter().map(serde_json::Value::as_f64).collect());
            let xyz = xyz.ok_or_else(|| {
                format!(
                    "field {name:?}: expected an array of 3 numbers, got {}",
                    brief(v)
                )
            })?;
            Ok([
                to_f32(name, xyz[0])?,
                to_f32(name, xyz[1])?,
                to_f32(name, xyz[2])?,
            ])
        };
        Ok(match op {
            "nearest_object" => ObjectQuery::NearestObject {
                point: point("point")?,
            },
            "objects_within" => ObjectQuery::ObjectsWithin {
                point: point("point")?,
                radius: number("radius")?,
            },
            "visible_objects" => ObjectQuery::VisibleObjects {
                eye: point("eye")?,
                dir: point("dir")?,
                half_angle_deg: number("half_angle_deg")?,
                range: number("range")?,
            },
            _ => {
                let v = get("label")?;
                ObjectQuery::ObjectsWithLabel {
                    label: v
                        .as_str()
                        .ok_or_else(|| {
                            format!("field \"label\": expected a string, got {}", brief(v))
                        })?
                        .to_owned(),
                }
            }
        })
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
