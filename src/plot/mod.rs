//! `hvi plot RUN_DIR`: pictures of a run written by `hvi solve`, each as PNG and SVG.
//!
//! * 2D, `deformed.png`/`.svg`: the last frame's mesh deformed by a magnified displacement,
//!   coloured by the run's active scalar (`output.active_scalar`: von Mises by default, |u| or
//!   |σ|; docs/method.md §12.3), with a colour bar, the field's name,
//!   the time, the magnification and — when the scene has a bound — the foundation
//!   u_ν = g drawn at the same magnification.
//! * 2D, `gamma3.png`/`.svg`: u_ν and the contact pressure along Γ₃ against arc length (so a
//!   vertical or curved Γ₃ works) at chosen times (`--times`; for the paper's scene the times of
//!   its Fig. 2, docs/example.md), with the bound g in the u_ν panel.
//! * 2D, `history.png`/`.svg` (three output times or more): the largest u_ν on Γ₃ at every output
//!   time — an indentation's depth, a creep curve — on a logarithmic time axis when the times span
//!   two decades or more.
//! * 2D with friction, `gamma3_zones.png`/`.svg`: the stick, slip and separated nodes along Γ₃
//!   at every output time (docs/method.md §17.5).
//! * 3D, `gamma3_map.png`/`.svg`: u_ν and the pressure over Γ₃ as colour maps (with friction, a
//!   third panel: the stick and slip zones).
//!
//! Everything is read from the run directory: `solution.pvd` and its last `.vtu`,
//! `gamma3.csv`, `scene.toml` (the effective scene) and `summary.json`. Text in the PNG files is
//! drawn with the pixel glyphs of `kit.rs` (no system font is needed).

mod deformed;
mod error;

mod gamma3;

mod history;

pub mod kit;

mod obstacle;

mod read;

mod run;

pub mod surface;

mod zones;

pub use deformed::{render_deformed, DeformedPicture};
pub use error::PlotError;

pub use kit::{colour_map, sci};

pub use obstacle::{level_set_segments, magnify_from};

pub use read::{arc_length, read_gamma3, Gamma3};

pub use run::{default_scale, plot_run, PlotOptions};
