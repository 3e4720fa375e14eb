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
    // any volume element (also one hvi does not compute with: second-order tetrahedra, prisms
    // or pyramids) makes a 3D mesh, whose reader then names what to do about the element
    if raw
        .element_types
        .iter()
        .any(|&t| crate::mesh::element_type_info(t).is_some_and(|(_, _, dim)| dim == 3))
    {
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

#[cfg(test)]
mod msh41_tests {
    //! The MSH 4.1 reader (msh41.rs) through the dispatcher: binary in both byte orders and
    //! size_t widths reads like ASCII, and every cut is an error.
    use super::parse_msh;
    use crate::mesh::AnyMesh;
    use std::path::Path;

    /// Two unit squares, Γ₃ (tag 3) the bottom curve, Ω (tag 5) the surface; node tags are given
    /// in a shuffled order to check that they are kept.
    const NODES: [(u64, [f64; 3]); 6] = [
        (4, [0.0, 1.0, 0.0]),
        (1, [0.0, 0.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
        (3, [2.0, 0.0, 0.0]),
        (6, [2.0, 1.0, 0.0]),
        (5, [1.0, 1.0, 0.0]),
    ];
    const LINES: [[u64; 3]; 2] = [[1, 1, 2], [2, 2, 3]];
    const QUADS: [[u64; 5]; 2] = [[3, 1, 2, 5, 4], [4, 2, 3, 6, 5]];
    const NAMES: &str = "$PhysicalNames\n2\n1 3 \"Gamma3\"\n2 5 \"Omega\"\n$EndPhysicalNames\n";

    fn ascii() -> String {
        let mut s = format!("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n{NAMES}");
        s += "$Entities\n0 1 1 0\n1 0 0 0 2 0 0 1 3 0\n1 0 0 0 2 1 0 1 5 0\n$EndEntities\n";
        s += "$Nodes\n1 6 1 6\n2 1 0 6\n";
        for (t, _) in NODES {
            s += &format!("{t}\n");
        }
        for (_, c) in NODES {
            s += &format!("{:?} {:?} {:?}\n", c[0], c[1], c[2]);
        }
        s += "$EndNodes\n$Elements\n2 4 1 4\n1 1 1 2\n";
        for l in LINES {
            s += &format!("{} {} {}\n", l[0], l[1], l[2]);
        }
        s += "2 1 3 2\n";
        for q in QUADS {
            s += &format!("{} {} {} {} {}\n", q[0], q[1], q[2], q[3], q[4]);
        }
        s + "$EndElements\n"
    }

    /// The same mesh as binary MSH 4.1 with a size_t of `st` bytes in either byte order.
    fn binary(st: usize, little: bool) -> Vec<u8> {
        let mut b = format!("$MeshFormat\n4.1 1 {st}\n").into_bytes();
        let order = |mut v: Vec<u8>| {
            if !little {
                v.reverse();
            }
            v
        };
        let int = |b: &mut Vec<u8>, v: i32| b.extend(order(v.to_le_bytes().to_vec()));
        let size = |b: &mut Vec<u8>, v: u64| b.extend(order(v.to_le_bytes()[..st].to_vec()));
        let float = |b: &mut Vec<u8>, v: f64| b.extend(order(v.to_le_bytes().to_vec()));
        int(&mut b, 1);
        b.extend(format!("\n$EndMeshFormat\n{NAMES}$Entities\n").bytes());
        for n in [0, 1, 1, 0] {
            size(&mut b, n);
        }
        for (phys, max_y) in [(3, 0.0), (5, 1.0)] {
            int(&mut b, 1);
            for v in [0.0, 0.0, 0.0, 2.0, max_y, 0.0] {
                float(&mut b, v);
            }
            size(&mut b, 1);
            int(&mut b, phys);
            size(&mut b, 0);
        }
        b.extend(b"\n$EndEntities\n$Nodes\n");
        for n in [1, 6, 1, 6] {
            size(&mut b, n);
        }
        for v in [2, 1, 0] {
            int(&mut b, v);
        }
        size(&mut b, 6);
        for (t, _) in NODES {
            size(&mut b, t);
        }
        for (_, c) in NODES {
            for v in c {
                float(&mut b, v);
            }
        }
        b.extend(b"\n$EndNodes\n$Elements\n");
        for n in [2, 4, 1, 4] {
            size(&mut b, n);
        }
        for (dim, ty, elements) in [(1, 1, LINES.map(|l| l.to_vec())), (2, 3, QUADS.map(|q| q.to_vec()))] {
            for v in [dim, 1, ty] {
                int(&mut b, v);
            }
            size(&mut b, 2);
            for e in elements {
                for t in e {
                    size(&mut b, t);
                }
            }
        }
        b.extend(b"\n$EndElements\n");
        b
    }

    #[test]
    fn binary_in_both_byte_orders_and_size_t_widths_reads_like_ascii() {
        let Ok(AnyMesh::Two(a)) = parse_msh(Path::new("a.msh"), ascii().as_bytes()) else {
            panic!("the ASCII file does not read as a 2D mesh");
        };
        assert_eq!(a.points.len(), 6);
        assert_eq!(a.points[3], [0.0, 1.0], "points are in tag order");
        assert_eq!(a.cells.len(), 2);
        assert_eq!(a.cell_tags, vec![3, 4]);
        let names: Vec<_> = a.groups.iter().map(|g| (g.dim, g.tag, g.name.clone())).collect();
        assert_eq!(names, vec![(1, 3, Some("Gamma3".into())), (2, 5, Some("Omega".into()))]);
        assert_eq!(a.groups[0].facets.len(), 2);
        for (st, little) in [(8, true), (8, false), (4, true), (4, false)] {
            let b = binary(st, little);
            match parse_msh(Path::new("b.msh"), &b) {
                Ok(AnyMesh::Two(m)) => assert_eq!(
                    (&m.points, &m.cells, &m.cell_tags, &m.groups),
                    (&a.points, &a.cells, &a.cell_tags, &a.groups),
                    "size_t {st}, little endian {little}"
                ),
                Ok(_) => panic!("size_t {st}, little endian {little}: not 2D"),
                Err(e) => panic!("size_t {st}, little endian {little}: {e}"),
            }
            // every cut (short of the final line break) is an error naming the file, never a panic
            for cut in (0..b.len() - 1).step_by(3) {
                let e = parse_msh(Path::new("b.msh"), &b[..cut]).expect_err("a cut file");
                assert!(e.to_string().contains("b.msh"), "{e}");
            }
        }
    }
}
