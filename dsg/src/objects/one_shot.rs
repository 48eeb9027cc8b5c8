//! One-query shortcuts: each builds an [`Objects`] for a single query.

use super::{ObjectQueryError, Objects};
use ygg_store::{NodeId, Point, SceneView};

/// [`Objects::nearest_object`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::nearest_object`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// let id = objects::nearest_object(&g, [5.0, 5.0, 1.0])?.expect("the office has objects");
/// assert!(objects::objects_within(&g, [5.0, 5.0, 1.0], 100.0)?.contains(&id));
/// # Ok(()) }
/// ```
pub fn nearest_object<V: SceneView>(
    view: &V,
    point: Point,
) -> Result<Option<NodeId>, ObjectQueryError> {
    Objects::new(view).nearest_object(point)
}

/// [`Objects::objects_within`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::objects_within`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// let all = objects::objects_within(&g, [20.0, 12.0, 1.5], 1000.0)?;
/// assert_eq!(all.len(), 34); // every object of the tiny office
/// assert!(objects::objects_within(&g, [500.0, 0.0, 0.0], 1.0)?.is_empty());
/// # Ok(()) }
/// ```
pub fn objects_within<V: SceneView>(
    view: &V,
    point: Point,
    radius: f32,
) -> Result<Vec<NodeId>, ObjectQueryError> {
    Objects::new(view).objects_within(point, radius)
}

/// [`Objects::visible_objects`] on `view` (builds an [`Objects`] for one query).
///
/// # Errors
/// As [`Objects::visible_objects`].
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// // A full sphere of view sees everything in range; a zero direction is an error.
/// let seen = objects::visible_objects(&g, [20.0, 12.0, 1.5], [1.0, 0.0, 0.0], 180.0, 1000.0)?;
/// assert_eq!(seen.len(), 34);
/// assert!(objects::visible_objects(&g, [0.0; 3], [0.0; 3], 30.0, 5.0).is_err());
/// # Ok(()) }
/// ```
pub fn visible_objects<V: SceneView>(
    view: &V,
    eye: Point,
    dir: Point,
    half_angle_deg: f32,
    range: f32,
) -> Result<Vec<NodeId>, ObjectQueryError> {
    Objects::new(view).visible_objects(eye, dir, half_angle_deg, range)
}

/// [`Objects::objects_with_label`] on `view` (builds an [`Objects`] for one query).
///
/// # Examples
/// ```
/// # use ygg_dsg::{office, layout::{self, Layout}, objects};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let g = layout::build(&office::generate(office::OfficeParams { seed: 7, scale: 0.02 }), Layout::Mint)?;
/// assert_eq!(objects::objects_with_label(&g, "light").len(), 4);
/// assert!(objects::objects_with_label(&g, "absent").is_empty());
/// # Ok(()) }
/// ```
pub fn objects_with_label<V: SceneView>(view: &V, label: &str) -> Vec<NodeId> {
    Objects::new(view).objects_with_label(label)
}
