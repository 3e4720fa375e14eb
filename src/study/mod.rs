//! Convergence studies (docs/method.md §6, the paper's Tables 1–2): runs along refinement paths in
//! h and in k, their errors against a reference run or an exact solution, observed orders,
//! and the tables (Markdown, CSV) and plots (SVG, PNG) that report them.
//!
//! * [`interpolate`]: point location and interpolation of P1/Q1 fields between meshes;
//! * [`runner`]: one run ([`run`]) and a [`Study`] that evaluates runs as they are added;
//! * [`level`]: a run's time levels ([`TimeLevel`]: uniform, per decade, to a tolerance) and the
//!   parameter its order is measured against;
//! * [`report`]: Markdown and CSV tables;
//! * [`plot`]: log–log error plots, the Γ₃ normal displacement, the deformed mesh;
//! * [`target`]: the error and cost models of a study and the cheapest run for a target error.
//!
//! ```no_run
//! use hvi::mesh::structured::{rectangle, CellShape};
//! use hvi::scene::Scene;
//! use hvi::study::{self, Keep, Refinement, RunOptions, Study};
//! let scene = |n: usize| Scene::load(None, &[format!("time.steps={n}")]).unwrap();
//! let reference = study::run_with(rectangle(2.0, 1.0, 128, 64, CellShape::Quad), &scene(64),
//!     &RunOptions { label: "reference".into(), h: Some(1.0 / 64.0), keep: Keep::MultiplesOf(0.0625) }).unwrap();
//! let mut s = Study::against_run(reference);
//! let mut path = vec![];
//! for n in [8, 16, 32] {
//!     let r = study::run(rectangle(2.0, 1.0, 2 * n, n, CellShape::Quad), &scene(64), format!("h=1/{n}")).unwrap();
//!     path.push(s.add_run(&r).unwrap());
//! }
//! s.add_path("h", Refinement::H, path).unwrap();
//! println!("{}", study::report::markdown(&s.rows()));
//! ```

mod advice;

pub mod execute;

mod format;

pub mod interpolate;

pub mod level;

pub mod plot;

pub mod report;

pub mod runner;

pub mod spec;

pub mod target;

pub use advice::Targets;

pub use interpolate::{boundary_sagitta, interpolate_nodal, Extension, Locator, Transfer};

pub use level::TimeLevel;

pub use runner::run_plan;

pub use runner::{
    observed_order, run, run_with, EvaluatedRun, ExactField, Keep, Reference, Refinement, RefinementPath, Row,
    RunErrors, RunOptions, RunRecord, RunSummary, Study, StudyPlan,
};

use crate::fem::norms::{errors, FieldErrors};
use crate::mesh::Mesh;

/// The H¹ seminorm and L² norm of `u_ref − u_carried`, two nodal fields on the reference
/// mesh (the carried one typically from [`interpolate_nodal`]).
pub fn seminorm_errors<const D: usize>(reference: &Mesh<D>, u_ref: &[[f64; D]], u_carried: &[[f64; D]]) -> FieldErrors {
    assert_eq!(
        u_ref.len(),
        reference.points.len(),
        "reference field and mesh differ in size"
    );
    assert_eq!(
        u_carried.len(),
        reference.points.len(),
        "carried field and reference mesh differ in size"
    );
    let difference: Vec<[f64; D]> = u_ref
        .iter()
        .zip(u_carried)
        .map(|(a, b)| std::array::from_fn(|d| a[d] - b[d]))
        .collect();
    errors(&reference.cells, &reference.points, &difference, |_| {
        ([0.0; D], [[0.0; D]; D])
    })
}
