//! Spark-DSG JSON: `import` (parse, check and convert to [`crate::DsgGraph`]; the checks
//! and conversion are shared with the binary importer) and `export` (the inverse).

mod export;
mod import;

pub use export::{DsgExportError, to_json_bytes, write_json, write_json_to};
pub(crate) use export::{box_axis, layer_keys, layer_names, name_to_write};
pub(crate) use import::{build_graph, build_node_in_layer, parse_json_impl};
pub use import::{parse_json, parse_json_with, parse_json_with_progress};
