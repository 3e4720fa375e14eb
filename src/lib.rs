//! # hvi — quasistatic contact of viscoelastic bodies with long memory
//!
//! A finite-element solver for history-dependent hemivariational inequalities (Xu, Huang,
//! Han et al., CAMWA 2019): a viscoelastic body with memory, σ = Aε(u) + ∫₀ᵗ B(t−s)ε(u(s))ds,
//! in frictionless contact with a rigid foundation covered by a non-monotone compliant layer.
//!
//! The pipeline: a gmsh mesh ([`mesh`]) and a TOML scene ([`scene`]) become a
//! [`solver::Simulation`] holding only the effects the scene names; [`solver::timeloop::run`]
//! assembles ([`fem`]), factorises once ([`linalg`]), and per time step updates the memory
//! term ([`history`]) and solves the contact law ([`contact`]); [`output`] writes the VTK
//! series. The mathematics is in `docs/method.md`; comments name its sections.
//!
//! ```no_run
//! use hvi::{mesh, scene::Scene, solver::{Simulation, timeloop}, app::MemorySink};
//! let scene = Scene::load(None, &["time.steps=8".to_string()]).unwrap();
//! let mesh = mesh::read_mesh::<2>(std::path::Path::new("meshes/rect_q1_h16.msh")).unwrap();
//! let sim = Simulation::new(&scene, mesh).unwrap();
//! let mut sink = MemorySink::default();
//! let stats = timeloop::run(&sim, &mut sink, None).unwrap();
//! println!("{} Newton iterations in all", stats.newton_iterations.iter().sum::<usize>());
//! ```

// Index loops over the D components and the nodes of a cell read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod alloc;
pub mod app;
pub mod contact;
pub mod expr;
pub mod fem;
pub mod history;
pub mod linalg;
pub mod material;
pub mod mesh;
pub mod output;
#[cfg(feature = "petsc")]
pub mod petsc;
pub mod plot;
pub mod scene;
pub mod solver;
pub mod study;
pub mod time;
