//! What can go wrong reading a mesh or asking it for a boundary part.
//!
//! Every message names the file (for generated meshes, a label such as `<rectangle 16x8>`),
//! where in it the problem is (line number for ASCII files, section, node or element tag), and
//! what to do about it.

use std::path::PathBuf;

/// An error of the mesh module. `Send + Sync + 'static`, so it can cross threads and be boxed.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read at all.
    #[error("cannot read mesh file {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Not a gmsh MSH file, or a version/encoding hvi does not read.
    #[error("{}: {detail}", path.display())]
    UnsupportedFormat { path: PathBuf, detail: String },
    /// The file is malformed: a token that does not parse, a truncated section, a count in a
    /// header that the file is too short to hold.
    #[error("{}: {place}: {detail}", path.display())]
    Syntax {
        path: PathBuf,
        place: String,
        detail: String,
    },
    /// An element type hvi cannot compute with (higher order, 3D, ...).
    #[error("{}: {place}: {detail}", path.display())]
    UnsupportedElement {
        path: PathBuf,
        place: String,
        element_type: i32,
        detail: String,
    },
    /// The file parses but the mesh is not usable: non-finite or non-planar coordinates,
    /// duplicate node tags, elements referring to missing nodes, inverted or degenerate cells.
    #[error("{}: {place}: {detail}", path.display())]
    Invalid {
        path: PathBuf,
        place: String,
        detail: String,
    },
    /// A physical group asked for by a scene does not exist.
    #[error("{}: there is no physical group {wanted} of dimension {dim}; the mesh has {available}", path.display())]
    GroupNotFound {
        path: PathBuf,
        wanted: String,
        dim: u8,
        available: String,
    },
    /// The mesh is not one conforming body (docs/method.md §16.3): its defects, severe first.
    #[error("{}: the mesh is not one conforming body: {detail}; if this is intended, pass --accept-mesh-defects to run anyway", path.display())]
    Defects { path: PathBuf, detail: String },
    /// A group used as a boundary part is not on the boundary of the body.
    #[error("{}: {group} is not on the boundary of the body: {detail}", path.display())]
    NotBoundary {
        path: PathBuf,
        group: String,
        detail: String,
    },
}

#[cfg(test)]
mod tests {
    #[test]
    fn error_is_send_sync_static() {
        fn check<T: Send + Sync + 'static + std::error::Error>() {}
        check::<super::MeshError>();
    }
}
