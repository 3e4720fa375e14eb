//! The mesh: gmsh MSH files (4.1 ASCII and binary, 2.2 ASCII) and built-in structured meshers,
//! in two or three dimensions (docs/method.md §2, §8).
//!
//! [`read_msh`] reads a file into an [`AnyMesh`]: a [`Mesh<2>`] when the file has only points,
//! lines, triangles and quadrangles in a plane z = const, a [`Mesh<3>`] when it has tetrahedra or
//! hexahedra. Points are dense and 0-based (in ascending order of the gmsh node tags), every cell of
//! the body's dimension is a positively oriented [`Cell`], and the physical groups keep their
//! `$PhysicalNames`. A scene refers to a group by name or tag ([`GroupSelector`]);
//! [`Mesh::boundary`] turns a group of facets (curves in 2D, surfaces in 3D) into an oriented
//! [`BoundaryPart`] with outward normals and nodal quadrature weights.
//!
//! Only first-order elements are read: points (gmsh type 15), 2-node lines (1), 3-node
//! triangles (2), 4-node quadrilaterals (3), 4-node tetrahedra (4), 8-node hexahedra (5), 6-node
//! prisms (6) and 5-node pyramids (7); anything else is an error that says how to re-mesh. Every problem found is reported with the
//! file, the place (line number for ASCII files, node or element tag) and what to do: hvi never
//! panics on a bad file and never allocates in proportion to a count in a header that the file
//! is too short to hold.
//!
//! Cells are not reordered or repaired, with one exception: if *every* cell of the file is
//! inverted (a 2D surface whose normal points to −z, a 3D mesh written with the other
//! handedness), all cells are flipped. A mesh with only some inverted cells is an error naming
//! the first of them.

mod build;

mod cell;

mod conformity;

pub mod element;

mod error;

mod gmsh;

mod group;

mod kind;

mod model;

mod msh22;

mod msh41;

mod physical_names;

pub mod quadrature;

mod read;

mod second_order;

pub mod structured;

pub mod topology;
pub mod vector;

pub use cell::{Cell, Facet};

pub use kind::CellKind;

pub use conformity::MeshDefect;

pub use error::MeshError;

pub use group::GroupSelector;

pub use model::{AnyMesh, Mesh, PhysicalGroup};

pub use read::{parse_mesh, parse_msh, read_mesh, read_msh};

pub(crate) use topology::facet_integrals;

pub use topology::BoundaryPart;

// what the MSH readers share (msh22.rs, msh41.rs, physical_names.rs read them through here)

pub(crate) use build::RawMesh;

pub(crate) use gmsh::{element_type_info, line_of, trim, Header, Lines, Origin, Places};

pub(crate) use model::fmt_point;
