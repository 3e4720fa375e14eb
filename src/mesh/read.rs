//! Reading a gmsh file: the version decides the reader (MSH 4.1 or 2.2), the dimension the
//! mesh type.

use super::build::build_mesh;
use super::gmsh::Version;
use crate::mesh::msh22;
use crate::mesh::msh41;
use crate::mesh::AnyMesh;
use crate::mesh::Header;
use crate::mesh::Mesh;
use crate::mesh::MeshError;
use std::path::Path;

/// Reads a gmsh MSH file: 4.1 (ASCII or binary) or 2.2 (ASCII), chosen from `$MeshFormat`; the
/// dimension from its elements.
pub fn read_msh(path: &Path) -> Result<AnyMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_msh(path, &bytes)
}

/// Reads a gmsh MSH file that must hold a D-dimensional body; a file of the other dimension is
/// an error that says so.
pub fn read_mesh<const D: usize>(path: &Path) -> Result<Mesh<D>, MeshError> {
    into_dim(read_msh(path)?, path)
}

/// Parses the bytes of an MSH file already in memory; `path` is used in messages only.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<AnyMesh, MeshError> {
    let header = Header::parse(path, bytes)?;
    let raw = match header.version {
        Version::V2 => msh22::parse(path, bytes, header.body)?,
        Version::V41 => msh41::parse(path, bytes, &header)?,
    };
    if raw.element_types.iter().any(|&t| matches!(t, 4 | 5)) {
        build_mesh::<3>(path, raw).map(AnyMesh::Three)
    } else {
        build_mesh::<2>(path, raw).map(AnyMesh::Two)
    }
}

/// [`parse_msh`] for a body of dimension D.
pub fn parse_mesh<const D: usize>(path: &Path, bytes: &[u8]) -> Result<Mesh<D>, MeshError> {
    into_dim(parse_msh(path, bytes)?, path)
}

fn into_dim<const D: usize>(mesh: AnyMesh, path: &Path) -> Result<Mesh<D>, MeshError> {
    let got = mesh.dim();
    let any: Box<dyn std::any::Any> = match mesh {
        AnyMesh::Two(m) => Box::new(m),
        AnyMesh::Three(m) => Box::new(m),
    };
    any.downcast::<Mesh<D>>().map(|m| *m).map_err(|_| MeshError::Invalid {
        path: path.to_path_buf(),
        place: "$Elements".into(),
        detail: format!("this is a {got}D mesh, but a {D}D mesh is needed here"),
    })
}
