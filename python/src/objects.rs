//! `yggdrasil.ObjectQueries` (`scene.objects`): the object contract of `ygg query`
//! (`ygg_dsg::objects`), one query at a time or in batches without the GIL.

use std::sync::Arc;

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use ygg_dsg::objects::{ObjectQuery, ObjectQueryError};
use ygg_store::NodeId;

use crate::batch;
use crate::convert::{point, points};
use crate::errors::{QueryError, query_error};
use crate::snapshot::ObjectCatalog;

/// A ragged batch answer: `offsets` (n + 1, int64) into the concatenated `ids` (uint64);
/// row i's ids are `ids[offsets[i]:offsets[i + 1]]`.
type Ragged<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<u64>>);

fn ids(nodes: Vec<NodeId>) -> Vec<u64> {
    nodes.into_iter().map(|n| n.0).collect()
}

fn ragged(py: Python<'_>, rows: Vec<Vec<NodeId>>) -> Ragged<'_> {
    let mut offsets = Vec::with_capacity(rows.len() + 1);
    offsets.push(0i64);
    let mut flat = Vec::new();
    for row in rows {
        flat.extend(row.into_iter().map(|n| n.0));
        offsets.push(flat.len() as i64);
    }
    (offsets.into_pyarray(py), flat.into_pyarray(py))
}

/// The object queries of a scene (`scene.objects`, or `scene.objects_in(room)` for one
/// sub-tree): answers are Spark-DSG object ids, ascending, the same on every layout, and
/// exactly what `ygg query` answers. The catalog of object layers is built once
/// per scene and kept.
#[pyclass(frozen, module = "yggdrasil", name = "ObjectQueries")]
pub struct ObjectQueries {
    catalog: Arc<ObjectCatalog>,
}

impl ObjectQueries {
    /// Queries over `catalog`.
    pub fn new(catalog: Arc<ObjectCatalog>) -> Self {
        ObjectQueries { catalog }
    }

    /// The ids answering one query, as `ygg query` answers it.
    pub fn answer(&self, q: &ObjectQuery) -> PyResult<Vec<u64>> {
        self.catalog
            .with_dependent(|_, objects| objects.answer(q))
            .map(ids)
            .map_err(|e| query_error(&e))
    }

    fn run<T>(
        &self,
        f: impl FnOnce(&crate::snapshot::SceneObjects<'_>) -> Result<T, ObjectQueryError>,
    ) -> PyResult<T> {
        self.catalog
            .with_dependent(|_, objects| f(objects))
            .map_err(|e| query_error(&e))
    }
}

#[pymethods]
impl ObjectQueries {
    /// The object with the vertex closest to `point` (ties to the smaller id), or `None`
    /// when the scene has no object with a vertex.
    fn nearest(&self, point: &Bound<'_, PyAny>) -> PyResult<Option<u64>> {
        let p = self::point(point, "point")?;
        self.run(|o| o.nearest_object(p)).map(|n| n.map(|n| n.0))
    }

    /// Every object with a vertex at distance `<= radius` from `point`, ascending.
    fn within(&self, point: &Bound<'_, PyAny>, radius: f32) -> PyResult<Vec<u64>> {
        let p = self::point(point, "point")?;
        self.run(|o| o.objects_within(p, radius)).map(ids)
    }

    /// Every object with a vertex in the view cone (apex `eye`, direction `dir`,
    /// `half_angle_deg` in degrees, `range` in metres), ascending.
    fn visible(
        &self,
        eye: &Bound<'_, PyAny>,
        dir: &Bound<'_, PyAny>,
        half_angle_deg: f32,
        range: f32,
    ) -> PyResult<Vec<u64>> {
        let (eye, dir) = (point(eye, "eye")?, point(dir, "dir")?);
        self.run(|o| o.visible_objects(eye, dir, half_angle_deg, range))
            .map(ids)
    }

    /// Every object carrying `label` (its labelspace name or decimal semantic label),
    /// ascending.
    fn with_label(&self, label: &str) -> Vec<u64> {
        self.catalog
            .with_dependent(|_, objects| ids(objects.objects_with_label(label)))
    }

    /// Every object node of the catalog, ascending.
    fn ids(&self) -> Vec<u64> {
        self.catalog
            .with_dependent(|_, objects| ids(objects.objects()))
    }

    /// `nearest` for each row of `points` (an `(n, 3)` array), without the GIL: an `int64`
    /// array of n ids, `NO_NODE` (-1) where there is no object.
    fn nearest_many<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let queries = self::points(points, "points")?;
        let catalog = Arc::clone(&self.catalog);
        let answers = py.detach(move || {
            catalog
                .with_dependent(|_, objects| batch::map(&queries, |p| objects.nearest_object(*p)))
        });
        let found = answers.map_err(|e| query_error(&e))?;
        Ok(batch::signed_ids(found)?.into_pyarray(py))
    }

    /// `within` for each row of `points` with one `radius`, without the GIL:
    /// `(offsets, ids)`, row i's ids being `ids[offsets[i]:offsets[i + 1]]`.
    fn within_many<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        radius: f32,
    ) -> PyResult<Ragged<'py>> {
        let queries = self::points(points, "points")?;
        let catalog = Arc::clone(&self.catalog);
        let rows = py.detach(move || {
            catalog.with_dependent(|_, objects| {
                batch::map(&queries, |p| objects.objects_within(*p, radius))
            })
        });
        Ok(ragged(py, rows.map_err(|e| query_error(&e))?))
    }

    /// `visible` for each row of `eyes` and `dirs` (two `(n, 3)` arrays) with one
    /// half-angle and range, without the GIL: `(offsets, ids)` as `within_many`.
    fn visible_many<'py>(
        &self,
        py: Python<'py>,
        eyes: &Bound<'py, PyAny>,
        dirs: &Bound<'py, PyAny>,
        half_angle_deg: f32,
        range: f32,
    ) -> PyResult<Ragged<'py>> {
        let eyes = points(eyes, "eyes")?;
        let dirs = points(dirs, "dirs")?;
        if eyes.len() != dirs.len() {
            return Err(QueryError::new_err(format!(
                "eyes and dirs differ in length ({} and {})",
                eyes.len(),
                dirs.len()
            )));
        }
        let views: Vec<_> = eyes.into_iter().zip(dirs).collect();
        let catalog = Arc::clone(&self.catalog);
        let rows = py.detach(move || {
            catalog.with_dependent(|_, objects| {
                batch::map(&views, |(eye, dir)| {
                    objects.visible_objects(*eye, *dir, half_angle_deg, range)
                })
            })
        });
        Ok(ragged(py, rows.map_err(|e| query_error(&e))?))
    }
}
