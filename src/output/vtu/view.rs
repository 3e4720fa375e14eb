//! A frame as the VTU writers see it: the cells' topology, the fields checked against it, and
//! the buffers kept across frames.

use crate::mesh::{Cell, Facet};
use crate::output::{Field, FieldValues, Frame, OutputError, SurfaceFrame};
use std::collections::BTreeSet;
use std::path::Path;

/// The cells of a frame: volume (or area) cells of a grid, or the facets of a boundary part.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Topology<'a> {
    Cells(&'a [Cell]),
    Facets(&'a [Facet]),
}

impl Topology<'_> {
    pub(crate) fn len(&self) -> usize {
        match self {
            Topology::Cells(c) => c.len(),
            Topology::Facets(f) => f.len(),
        }
    }

    pub(crate) fn nodes(&self, i: usize) -> &[usize] {
        match self {
            Topology::Cells(c) => c[i].nodes(),
            // a second-order facet is drawn by its corners (polygons have no midside nodes)
            Topology::Facets(f) => f[i].corners(),
        }
    }

    /// The nodes of item i in VTK's order ([`crate::mesh::Cell::vtk_order`]).
    pub(crate) fn vtk_nodes(&self, i: usize) -> impl ExactSizeIterator<Item = usize> + '_ {
        let nodes = self.nodes(i);
        let order: &[usize] = match self {
            Topology::Cells(c) => c[i].vtk_order(),
            Topology::Facets(_) => &[0, 1, 2, 3][..nodes.len()],
        };
        order.iter().map(move |&k| nodes[k])
    }
}

/// What the encoder needs of a [`Frame`] or a [`SurfaceFrame`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct View<'a, const D: usize> {
    pub step: usize,
    pub time: f64,
    pub points: &'a [[f64; D]],
    pub topology: Topology<'a>,
    pub point_fields: &'a [Field<'a>],
    pub cell_fields: &'a [Field<'a>],
}

impl<'a, const D: usize> Frame<'a, D> {
    pub(crate) fn view(&'a self) -> View<'a, D> {
        View {
            step: self.step,
            time: self.time,
            points: self.points,
            topology: Topology::Cells(self.cells),
            point_fields: &self.point_fields,
            cell_fields: &self.cell_fields,
        }
    }
}

impl<'a, const D: usize> SurfaceFrame<'a, D> {
    pub(crate) fn view(&'a self) -> View<'a, D> {
        View {
            step: self.step,
            time: self.time,
            points: self.points,
            topology: Topology::Facets(self.facets),
            point_fields: &self.point_fields,
            cell_fields: &self.cell_fields,
        }
    }
}

/// The names of the components of an array of `components` values per entity, as written
/// (`ComponentName0`…): a 3-vector x y z, a row-major 3×3 tensor xx xy xz yx yy yz zx zy zz;
/// none for other counts (ParaView numbers them).
pub(crate) fn component_names(components: usize) -> &'static [&'static str] {
    match components {
        3 => &["x", "y", "z"],
        9 => &["xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"],
        _ => &[],
    }
}

impl FieldValues<'_> {
    /// The number of values (components × entities).
    pub fn len(&self) -> usize {
        match self {
            FieldValues::F64(v) => v.len(),
            FieldValues::I32(v) => v.len(),
        }
    }

    /// True if there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Checks everything that would make a broken or misleading file, before anything is written.
pub(crate) fn validate_view<const D: usize>(path: &Path, frame: &View<D>) -> Result<(), OutputError> {
    if !frame.time.is_finite() {
        return Err(OutputError::invalid_frame(
            path,
            format!(
                "step {} has the non-finite time {}; the time series needs a real time for every frame",
                frame.step, frame.time
            ),
        ));
    }
    if i32::try_from(frame.step).is_err() {
        return Err(OutputError::invalid_frame(
            path,
            format!("step {} does not fit the Int32 `step` field data", frame.step),
        ));
    }
    let n_points = frame.points.len();
    if let Some(p) = frame.points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(OutputError::invalid_frame(
            path,
            format!("point {p} has a non-finite coordinate {:?}", frame.points[p]),
        ));
    }
    let n_cells = frame.topology.len();
    for c in 0..n_cells {
        if let Some(&bad) = frame.topology.nodes(c).iter().find(|&&i| i >= n_points) {
            return Err(OutputError::invalid_frame(
                path,
                format!("cell {c} refers to node {bad}, but the frame has only {n_points} points"),
            ));
        }
    }
    if let Topology::Facets(f) = frame.topology {
        if f.iter().any(|x| x.len() == 2) && f.iter().any(|x| x.len() > 2) {
            return Err(OutputError::invalid_frame(
                path,
                "a boundary frame mixes edges and faces; its facets must all be edges (2D) or all faces (3D)",
            ));
        }
    }
    check_fields(path, "point", frame.point_fields, n_points)?;
    check_fields(path, "cell", frame.cell_fields, n_cells)
}

fn check_fields(path: &Path, location: &'static str, fields: &[Field], count: usize) -> Result<(), OutputError> {
    let mut seen = BTreeSet::new();
    for f in fields {
        if f.name.is_empty() || f.name.chars().any(char::is_control) {
            return Err(OutputError::invalid_frame(
                path,
                format!("{location} field name {:?} is empty or has control characters", f.name),
            ));
        }
        if !seen.insert(f.name) {
            return Err(OutputError::invalid_frame(
                path,
                format!("two {location} fields are named \"{}\"", f.name),
            ));
        }
        if f.components == 0 {
            return Err(OutputError::invalid_frame(
                path,
                format!("{location} field \"{}\" has 0 components", f.name),
            ));
        }
        let expected = f.components.saturating_mul(count);
        if f.values.len() != expected {
            return Err(OutputError::FieldLength {
                path: path.to_path_buf(),
                location,
                name: f.name.to_string(),
                components: f.components,
                count,
                expected,
                got: f.values.len(),
            });
        }
    }
    Ok(())
}

/// The byte buffers a [`super::SeriesWriter`] keeps across frames, so that every frame after
/// the first is built in memory that is already allocated and mapped: the appended block, and
/// (compressed) each array's uncompressed bytes before they are compressed.
#[derive(Default)]
pub(crate) struct VtuBuffer {
    pub(super) data: Vec<u8>,
    pub(super) scratch: Vec<u8>,
}

impl std::fmt::Debug for VtuBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "VtuBuffer({} + {} bytes reserved)",
            self.data.capacity(),
            self.scratch.capacity()
        )
    }
}

/// The arrays of a small two-cell frame, for the tests of the submodules.
#[cfg(test)]
pub(crate) struct Parts {
    pub(super) points: Vec<[f64; 2]>,
    pub(super) cells: Vec<Cell>,
    pub(super) u: Vec<f64>,
    pub(super) status: Vec<i32>,
    pub(super) stress: Vec<f64>,
}

#[cfg(test)]
impl Parts {
    pub(super) fn new() -> Self {
        Parts {
            points: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]],
            cells: vec![Cell::Quad4([0, 1, 2, 3]), Cell::Tri3([1, 4, 2])],
            u: (0..15)
                .map(|k| if k % 3 == 2 { 0.0 } else { 0.1 * k as f64 - 0.7 })
                .collect(),
            status: vec![-1, 0, 1, 2, i32::MAX],
            stress: (0..18).map(|k| (k as f64).sqrt() - 2.0).collect(),
        }
    }
}
