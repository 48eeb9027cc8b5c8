//! The exception hierarchy and the conversions of the Rust errors into it.
//!
//! | exception | raised for |
//! |---|---|
//! | `yggdrasil.Error` | base of every error below |
//! | `yggdrasil.FileError` | a file that cannot be read, is not a snapshot or Spark-DSG file, or fails validation |
//! | `yggdrasil.QueryError` | a query with bad input (non-finite point, negative radius, unknown node or layer, malformed query line) |
//! | `yggdrasil.MutationError` | a mutation the graph refuses (the graph is left unchanged) |
//! | `yggdrasil.TransportError` | shared memory: no writer, a rejected snapshot, a full `/dev/shm`, ... |
//! | `yggdrasil.WriterGoneError` | (a `TransportError`) the scene's writer exited; the last snapshot stays usable |
//!
//! Every message is the Rust error's own `Display`, with its sources appended.

use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::PyException;

create_exception!(
    _yggdrasil,
    Error,
    PyException,
    "Base class of every Yggdrasil error."
);
create_exception!(
    _yggdrasil,
    FileError,
    Error,
    "A file could not be read, is not what it claims, or failed validation."
);
create_exception!(
    _yggdrasil,
    QueryError,
    Error,
    "A query was given bad input (a non-finite point, a negative radius, an unknown node or layer, a malformed query)."
);
create_exception!(
    _yggdrasil,
    MutationError,
    Error,
    "The graph refused a mutation; it is left unchanged."
);
create_exception!(
    _yggdrasil,
    TransportError,
    Error,
    "Shared memory failed: no writer, a rejected snapshot, a full /dev/shm, ..."
);
create_exception!(
    _yggdrasil,
    WriterGoneError,
    TransportError,
    "The scene's writer exited or died; the last snapshot stays usable."
);

/// The message of `e` followed by each of its sources (`a: b: c`).
pub fn message(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    text
}

/// A `FileError` carrying `e`'s message.
pub fn file_error(e: &dyn std::error::Error) -> PyErr {
    FileError::new_err(message(e))
}

/// A `QueryError` carrying `e`'s message.
pub fn query_error(e: &dyn std::error::Error) -> PyErr {
    QueryError::new_err(message(e))
}

/// A `MutationError` carrying `e`'s message.
pub fn mutation_error(e: &dyn std::error::Error) -> PyErr {
    MutationError::new_err(message(e))
}

/// A `QueryError` naming a node the scene does not hold.
pub fn unknown_node(id: u64) -> PyErr {
    QueryError::new_err(format!("unknown node {id}"))
}

/// A `QueryError` naming a layer the scene does not hold.
pub fn unknown_layer(name: &str) -> PyErr {
    QueryError::new_err(format!("unknown layer {name:?}"))
}

/// A `TransportError` for a failed receive; `WriterGoneError` when the writer left.
pub fn receive_error(e: &ygg_reader::SceneReceiveError) -> PyErr {
    use ygg_reader::{ReceiveError, SceneReceiveError};
    match e {
        SceneReceiveError::Receive(ReceiveError::WriterGone { .. }) => {
            WriterGoneError::new_err(message(e))
        }
        _ => TransportError::new_err(message(e)),
    }
}

/// A `TransportError` carrying `e`'s message.
pub fn transport_error(e: &dyn std::error::Error) -> PyErr {
    TransportError::new_err(message(e))
}
