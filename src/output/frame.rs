//! What a frame of the series holds (docs/method.md §12): the body's (or Γ₃'s) fields as named
//! point and cell arrays, and numbers as hvi writes them (shortest round trip).

/// The largest zlib level of [`SeriesWriter::with_compression`].
pub const MAX_COMPRESSION_LEVEL: u32 = 9;

/// The values of a field, point- (or cell-) major: entity 0's components, then entity 1's, ...
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldValues<'a> {
    /// Written as `Float64`.
    F64(&'a [f64]),
    /// Written as `Int32` (status codes, flags, ids).
    I32(&'a [i32]),
}

/// A named field on the points or cells of a frame; `values.len()` must be
/// `components × count` (count of points or of cells), else writing the frame is an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field<'a> {
    pub name: &'a str,
    /// 1 for a scalar, 3 for a vector (ParaView's Warp By Vector wants 3), 9 for a tensor.
    pub components: usize,
    pub values: FieldValues<'a>,
    /// Marked as the active scalars of its PointData/CellData (`Scalars="…"`, what ParaView
    /// colours by) whatever its components; without a marked field the first 1-component one is.
    pub active: bool,
}

impl<'a> Field<'a> {
    /// The same field marked as the active scalars.
    pub fn active(self) -> Self {
        Field { active: true, ..self }
    }

    /// A `Float64` field.
    pub fn f64(name: &'a str, components: usize, values: &'a [f64]) -> Self {
        Field {
            name,
            components,
            values: FieldValues::F64(values),
            active: false,
        }
    }

    /// An `Int32` field.
    pub fn i32(name: &'a str, components: usize, values: &'a [i32]) -> Self {
        Field {
            name,
            components,
            values: FieldValues::I32(values),
            active: false,
        }
    }
}

/// One output step of a 2D solution.
#[derive(Clone, Debug)]
pub struct Frame<'a, const D: usize> {
    /// Names the file: `<basename>_<step:05>.vtu`.
    pub step: usize,
    /// The physical time, listed in the `.pvd` and `.vtu.series`; must be finite.
    pub time: f64,
    /// Written as 3D points (z = 0 for a 2D frame).
    pub points: &'a [[f64; D]],
    pub cells: &'a [crate::mesh::Cell],
    /// E.g. "displacement" with 3 components (z = 0) for ParaView's Warp By Vector.
    pub point_fields: Vec<Field<'a>>,
    /// E.g. "stress" with 9 components (a tensor), "von_mises" with 1.
    pub cell_fields: Vec<Field<'a>>,
}

/// One output step of a boundary part (e.g. Γ₃), written as a PolyData `.vtp`: its points are
/// the part's nodes only, its cells the part's facets (lines in 2D, triangles or quadrilaterals
/// in 3D), indexing into `points`.
#[derive(Clone, Debug)]
pub struct SurfaceFrame<'a, const D: usize> {
    /// Names the file: `<basename>_<step:05>.vtp`.
    pub step: usize,
    /// The physical time; must be finite.
    pub time: f64,
    pub points: &'a [[f64; D]],
    /// All edges (2D) or all faces (3D).
    pub facets: &'a [crate::mesh::Facet],
    pub point_fields: Vec<Field<'a>>,
    pub cell_fields: Vec<Field<'a>>,
}

/// Formats a number so that parsing it gives back the same `f64`: the shortest round-trip
/// decimal, plain (`0.25`, `1`, `-3.5e-3` → `-0.0035`) for magnitudes in [1e-5, 1e16) and zero,
/// in scientific notation (`1e-7`, `2.5e20`) otherwise; `NaN`, `inf`, `-inf` for the rest.
pub fn format_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The default zlib level of the `.vtu` files: 0, uncompressed (levels 1–9: zlib blocks of
/// 32 KiB, VTK's `vtkZLibDataCompressor` layout; the scene's `output.compress`). Measured sizes
/// and times: docs/outputs.md, "Files".
pub const DEFAULT_COMPRESSION_LEVEL: u32 = 0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.25,
            0.1 + 0.2,
            1e-7,
            -3.5e-3,
            2.5e20,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let s = format_number(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(format_number(1.0), "1");
        assert_eq!(format_number(0.25), "0.25");
        assert_eq!(format_number(1e-7), "1e-7");
    }
}
