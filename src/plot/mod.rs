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
//! * 3D, `gamma3_map.png`/`.svg`: u_ν and the pressure over Γ₃ as colour maps.
//!
//! Everything is read from the run directory: `solution.pvd` and its last `.vtu`,
//! `gamma3.csv`, `scene.toml` (the effective scene) and `summary.json`. Text in the PNG files is
//! drawn with the pixel glyphs of `kit.rs` (no system font is needed).

use crate::mesh::{Cell, Mesh};
use crate::output;
use crate::scene::Scene;
use crate::solver::SolveError;
pub mod kit;
pub mod surface;

pub use kit::{colour_map, sci};

use kit::{draw_text, draw_x_ticks, err, field_range, linear_ticks, minus_sign, tick_label, Lettering};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Options of `hvi plot`.
#[derive(Clone, Debug, Default)]
pub struct PlotOptions {
    /// Displacement magnification; None: the default of [`default_scale`].
    pub scale: Option<f64>,
    /// Times of the Γ₃ plot (the nearest output time is drawn); None: the paper's Fig. 2 times
    /// for the paper's scene, else up to six evenly spaced output times.
    pub times: Option<Vec<f64>>,
}

/// The times of the paper's Fig. 2 as docs/example.md reads them: t = j/8, j = 1 … 8.
pub const FIG2_TIMES: [f64; 8] = [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0];

/// The largest displacement is drawn as this fraction of the body's diagonal by default.
const VISIBLE_FRACTION: f64 = 0.05;

/// The default magnification: 1 (true scale) when the largest displacement is already at
/// least 5 % of the body's diagonal, else the largest of 1, 2, 5 × 10^j that draws it as at most
/// 5 % (so between 2 % and 5 %). 1 for a body that does not move.
pub fn default_scale(max_displacement: f64, diagonal: f64) -> f64 {
    if !(max_displacement > 0.0 && diagonal > 0.0) || max_displacement >= VISIBLE_FRACTION * diagonal {
        return 1.0;
    }
    let wanted = VISIBLE_FRACTION * diagonal / max_displacement;
    let mag = 10f64.powf(wanted.log10().floor());
    [5.0, 2.0, 1.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s <= wanted * (1.0 + 1e-12))
        .unwrap_or(mag)
        .max(1.0)
}

/// `hvi plot RUN_DIR`: draws the run (see the module documentation); returns the files written.
pub fn plot_run(run_dir: &Path, options: &PlotOptions) -> Result<Vec<PathBuf>, SolveError> {
    let fail = |what: String| SolveError::Setup(format!("{}: {what}", run_dir.display()));
    if let Some(s) = options.scale {
        if !(s.is_finite() && s > 0.0) {
            return Err(fail(format!(
                "--scale {s}: the magnification must be a positive number, e.g. --scale 10"
            )));
        }
    }
    if let Some(bad) = options.times.iter().flatten().find(|t| !t.is_finite()) {
        return Err(fail(format!(
            "--times: {bad} is not a time; give output times, e.g. --times 0.25,0.5,1"
        )));
    }
    let frames = output::read_pvd(&run_dir.join("solution.pvd")).map_err(|e| match e {
        output::OutputError::Read { source, .. } => fail(format!(
            "cannot read solution.pvd ({source}); is this an hvi output directory?"
        )),
        e => e.into(),
    })?;
    let (time, last) = frames
        .last()
        .cloned()
        .ok_or_else(|| fail("solution.pvd lists no frame".into()))?;
    let vtu = output::read_vtu_arrays(&run_dir.join(&last))?;
    let csv = std::fs::read_to_string(run_dir.join("gamma3.csv")).ok();
    let csv_3d = match &csv {
        Some(text) => Some(
            read_csv_header("gamma3.csv", text)
                .map_err(fail)?
                .iter()
                .any(|c| c == "z"),
        ),
        None => None,
    };
    if csv_3d == Some(true) || vtu.points.iter().any(|p| p[2] != 0.0) {
        return plot_3d(run_dir, &last);
    }
    let points: Vec<[f64; 2]> = vtu.points.iter().map(|p| [p[0], p[1]]).collect();
    let cells: Vec<Cell> = vtu
        .connectivity
        .iter()
        .map(|c| match c.len() {
            3 => Ok(Cell::Tri3([c[0], c[1], c[2]])),
            4 => Ok(Cell::Quad4([c[0], c[1], c[2], c[3]])),
            n => Err(fail(format!("{last}: a cell with {n} nodes"))),
        })
        .collect::<Result<_, _>>()?;
    let u: Vec<[f64; 2]> = match vtu.point_data.get("displacement") {
        Some((3, v)) => v.chunks(3).map(|c| [c[0], c[1]]).collect(),
        _ => return Err(fail(format!("{last} has no displacement field"))),
    };
    // the scene (for the active scalar, the bound, the obstacles and to recognise the paper's
    // example), if the run kept it
    let scene = Scene::load(Some(&run_dir.join("scene.toml")), &[]).ok();
    let active = scene
        .as_ref()
        .and_then(|s| s.output.active_scalar_name().map(str::to_string))
        .unwrap_or_else(|| "von_mises".into());
    let (field, values) = cell_colours(&active, &vtu, &cells, &u);
    let n_cells = cells.len();
    let mesh = Mesh {
        path: run_dir.join(&last),
        points,
        cells,
        cell_tags: (0..n_cells).collect(),
        groups: vec![],
    };
    let name = run_name(run_dir);
    let gamma3 = csv
        .as_deref()
        .map(|text| read_gamma3(text, &mesh))
        .transpose()
        .map_err(fail)?;
    // one layer without an obstacle: u_ν = g along the nodes' normals (with several groups or an
    // obstacle the foundation differs per group and is not drawn)
    let layer = scene.as_ref().and_then(|s| match s.contact.as_slice() {
        [one] if one.obstacle.is_none() => one.bound.as_ref(),
        _ => None,
    });
    let bound = match (layer, &gamma3) {
        (Some(spec), Some(g3)) => Some(crate::solver::bound::nodal_bound(
            spec,
            &g3.nodes,
            &mesh.points,
            "scene.toml",
            "contact.bound",
        )?),
        _ => None,
    };
    let (lo, hi) = bounding_box(&mesh.points);
    let diagonal = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
    let max_u = u.iter().map(|v| (v[0] * v[0] + v[1] * v[1]).sqrt()).fold(0.0, f64::max);
    let scale = options.scale.unwrap_or_else(|| default_scale(max_u, diagonal));
    let magnified = if scale == 1.0 {
        format!("displacement at true scale (largest |u| = {})", sci_text(max_u))
    } else {
        format!(
            "displacement magnified ×{} (largest |u| = {}, drawn as {:.1} % of the body's diagonal)",
            sci_text(scale),
            sci_text(max_u),
            100.0 * scale * max_u / diagonal.max(1e-300)
        )
    };
    let foundation = match (&gamma3, &bound) {
        (Some(g3), Some(g)) => Some(
            g3.order
                .iter()
                .map(|&k| {
                    let (p, nu) = (mesh.points[g3.nodes[k]], g3.normals[k]);
                    [p[0] + scale * g[k] * nu[0], p[1] + scale * g[k] * nu[1]]
                })
                .collect::<Vec<_>>(),
        ),
        _ => None,
    };
    let moved: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .zip(&u)
        .map(|(p, d)| [p[0] + scale * d[0], p[1] + scale * d[1]])
        .collect();
    let obstacles = match &scene {
        Some(scene) => obstacle_edges(
            scene,
            &mesh,
            &u,
            &moved,
            foundation.as_deref(),
            gamma3.as_ref(),
            time,
            scale,
        )?,
        None => vec![],
    };
    let picture = DeformedPicture {
        title: format!("{name}: {field} at t = {}", sci_text(time)),
        field,
        mesh: &mesh,
        displacement: &u,
        cell_values: &values,
        scale,
        scale_text: magnified,
        foundation,
        obstacles,
    };
    let (png, svg) = pictures(run_dir, "deformed")?;
    render_deformed(&png, Some(&svg), &picture).map_err(fail)?;
    let mut written = vec![png, svg];
    if let Some(g3) = &gamma3 {
        let available: Vec<f64> = g3.times.iter().map(|(t, _)| *t).collect();
        let paper = scene.as_ref().is_some_and(is_paper_scene);
        let (wanted, why) = match &options.times {
            Some(t) => (t.clone(), "chosen times".to_string()),
            None if paper => (FIG2_TIMES.to_vec(), "the paper's Fig. 2 times".to_string()),
            None => (evenly_spaced(&available, 6), "evenly spaced output times".to_string()),
        };
        let chosen = nearest_times(&available, &wanted);
        let start = mesh.points[g3.nodes[g3.order[0]]];
        let figure = Gamma3Figure {
            title: format!("{name}: u_ν and pressure on Γ₃ ({why})"),
            x_label: format!(
                "arc length s along Γ₃ from ({}, {})",
                sci_text(start[0]),
                sci_text(start[1])
            ),
            arc: g3.order.iter().map(|&k| g3.arc[k]).collect(),
            bound: bound.as_ref().map(|g| g3.order.iter().map(|&k| g[k]).collect()),
            curves: chosen
                .iter()
                .map(|&i| {
                    let (t, rows) = &g3.times[i];
                    (
                        *t,
                        g3.order.iter().map(|&k| rows[k].0).collect(),
                        g3.order.iter().map(|&k| rows[k].1).collect(),
                    )
                })
                .collect(),
        };
        let (png, svg) = pictures(run_dir, "gamma3")?;
        render_gamma3(&png, Some(&svg), &figure).map_err(fail)?;
        written.extend([png, svg]);
    }
    Ok(written)
}

/// The outlines of the scene's rigid obstacles at time `time` (moved by their motion a(t)) for
/// the deformed picture: the zero level set of φ(x − a(t)) over the body's box with a margin
/// of 15 % of its diagonal ([`level_set_segments`], 400 cells along the longer side), moved by
/// [`magnify_from`] like the displacement, and kept where it falls within 8 % of the picture's
/// diagonal around the body (docs/method.md §12.4).
#[allow(clippy::too_many_arguments)]
fn obstacle_edges(
    scene: &Scene,
    mesh: &Mesh<2>,
    u: &[[f64; 2]],
    moved: &[[f64; 2]],
    foundation: Option<&[[f64; 2]]>,
    gamma3: Option<&Gamma3>,
    time: f64,
    scale: f64,
) -> Result<Vec<ObstacleEdge>, SolveError> {
    if scene.contact.iter().all(|c| c.obstacle.is_none()) {
        return Ok(vec![]);
    }
    let deformed: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .zip(u)
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1]])
        .collect();
    let grow = |(lo, hi): ([f64; 2], [f64; 2]), by: f64| {
        let m = by * ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
        ([lo[0] - m, lo[1] - m], [hi[0] + m, hi[1] + m])
    };
    let all: Vec<[f64; 2]> = mesh.points.iter().chain(&deformed).copied().collect();
    let (lo, hi) = grow(bounding_box(&all), 0.15);
    let mut shown: Vec<[f64; 2]> = mesh.points.iter().chain(moved).copied().collect();
    shown.extend(foundation.into_iter().flatten());
    let (plo, phi_) = grow(bounding_box(&shown), 0.08);
    let within = |p: [f64; 2]| p[0] >= plo[0] && p[0] <= phi_[0] && p[1] >= plo[1] && p[1] <= phi_[1];
    // Γ₃'s segments: consecutive nodes along it that are joined by a boundary edge
    let segments: Vec<[[f64; 2]; 2]> = gamma3.map_or_else(Vec::new, |g3| {
        g3.order
            .windows(2)
            .filter_map(|w| {
                let (p, q) = (mesh.points[g3.nodes[w[0]]], mesh.points[g3.nodes[w[1]]]);
                let d = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                ((g3.arc[w[1]] - g3.arc[w[0]] - d).abs() <= 1e-9 * d.max(1e-300) && d > 0.0).then_some([p, q])
            })
            .collect()
    });
    let diagonal = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
    let longer = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let cells = |extent: f64| ((400.0 * extent / longer).ceil() as usize).max(1);
    let mut edges = Vec::new();
    for (i, c) in scene.contact.iter().enumerate() {
        let Some(spec) = &c.obstacle else { continue };
        let key = format!("{}.obstacle", scene.contact_key(i));
        let obstacle = crate::solver::contact::obstacle_of::<2>(spec, &key, "scene.toml", diagonal)?;
        let mut a = [0.0; 2];
        for (k, e) in spec.motion().unwrap_or(&[]).iter().enumerate().take(2) {
            let expr = crate::scene::Expr::parse(e, &["t"])
                .map_err(|err| SolveError::Setup(format!("scene.toml: {key}.motion[{k}] = \"{e}\": {err}")))?;
            a[k] = expr.eval(&[time]);
        }
        let phi = |x: [f64; 2]| obstacle.phi(&[x[0] - a[0], x[1] - a[1]]);
        let mut found = level_set_segments(&phi, lo, hi, cells(hi[0] - lo[0]), cells(hi[1] - lo[1]));
        magnify_from(&mut found, &segments, scale);
        edges.extend(found.into_iter().filter(|e| within(e.a) && within(e.b)));
    }
    Ok(edges)
}

/// The PNG and SVG files of picture `stem` in the run directory, recorded in the run's manifest
/// before they are written, so that `hvi solve --overwrite` removes them with the run's own files
/// (docs/method.md §12.2).
fn pictures(run_dir: &Path, stem: &str) -> Result<(PathBuf, PathBuf), SolveError> {
    let (png, svg) = (format!("{stem}.png"), format!("{stem}.svg"));
    output::record_in_run(run_dir, &[&png, &svg])?;
    Ok((run_dir.join(png), run_dir.join(svg)))
}

/// The colour of each cell and the colour bar's name: the run's active scalar
/// (`output.active_scalar`, docs/method.md §12.3) — von Mises from the cells' values, the stress
/// by its Frobenius norm |σ| (ParaView's magnitude of the tensor), the displacement by |u| (the
/// mean over the cell's nodes) — falling back to |u| when the run has not written the field.
fn cell_colours(active: &str, vtu: &output::VtuContents, cells: &[Cell], u: &[[f64; 2]]) -> (String, Vec<f64>) {
    match (active, vtu.cell_data.get(active)) {
        ("von_mises", Some((1, v))) => ("von Mises stress".to_string(), v.clone()),
        ("stress", Some((9, v))) => (
            "|σ| (Frobenius norm of the stress)".to_string(),
            v.chunks(9)
                .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
                .collect(),
        ),
        _ => (
            if active == "displacement" {
                "|u|".to_string()
            } else {
                format!("|u| (no {active} in the run)")
            },
            cells
                .iter()
                .map(|c| {
                    let n = c.nodes();
                    n.iter()
                        .map(|&p| (u[p][0].powi(2) + u[p][1].powi(2)).sqrt())
                        .sum::<f64>()
                        / n.len() as f64
                })
                .collect(),
        ),
    }
}

/// A number as short text with the minus sign −.
fn sci_text(v: f64) -> String {
    minus_sign(sci(v))
}

/// The run's name for titles: its directory, with the mesh from summary.json when there is one.
fn run_name(run_dir: &Path) -> String {
    let dir = run_dir
        .file_name()
        .map_or_else(|| run_dir.display().to_string(), |n| n.to_string_lossy().into_owned());
    let mesh = std::fs::read_to_string(run_dir.join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok())
        .and_then(|v| v.get("mesh").and_then(|m| m.as_str()).map(str::to_string));
    match mesh {
        Some(m) => {
            let short = Path::new(&m)
                .file_name()
                .map_or(m.clone(), |f| f.to_string_lossy().into_owned());
            format!("run {dir} (mesh {short})")
        }
        None => format!("run {dir}"),
    }
}

/// Whether `scene` is the paper's example (the embedded default) up to its time steps and
/// output settings.
fn is_paper_scene(scene: &Scene) -> bool {
    let Ok(mut paper) = Scene::load(None, &[]) else {
        return false;
    };
    paper.time.steps = scene.time.steps;
    paper.output = scene.output.clone();
    paper.to_toml_string() == scene.to_toml_string()
}

/// Up to `count` of the times (t = 0, the unloaded start, left out when there are others),
/// evenly spaced by index, always including the last.
fn evenly_spaced(times: &[f64], count: usize) -> Vec<f64> {
    let later: Vec<f64> = times.iter().copied().filter(|t| *t != 0.0).collect();
    let later = if later.is_empty() { times.to_vec() } else { later };
    if later.len() <= count {
        return later;
    }
    (1..=count)
        .map(|i| later[(i * later.len()).div_ceil(count) - 1])
        .collect()
}

/// Indices of the available times nearest to each wanted time, without repeats, in time order.
fn nearest_times(available: &[f64], wanted: &[f64]) -> Vec<usize> {
    let mut chosen: Vec<usize> = wanted
        .iter()
        .filter_map(|w| {
            (0..available.len()).min_by(|&a, &b| (available[a] - w).abs().total_cmp(&(available[b] - w).abs()))
        })
        .collect();
    chosen.sort_unstable();
    chosen.dedup();
    chosen
}

fn bounding_box(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// Γ₃ of a 2D run as `gamma3.csv` gives it, located on the mesh.
pub struct Gamma3 {
    /// Mesh node of each Γ₃ node (in the CSV's order).
    pub nodes: Vec<usize>,
    /// Outward unit normal at each (from the boundary edges between Γ₃ nodes).
    pub normals: Vec<[f64; 2]>,
    /// Arc length of each from the start of Γ₃ (see [`arc_length`]).
    pub arc: Vec<f64>,
    /// The Γ₃ nodes (indices into `nodes`) in order along Γ₃.
    pub order: Vec<usize>,
    /// Per output time, (u_ν, pressure) of each node.
    pub times: Vec<(f64, Vec<(f64, f64)>)>,
}

/// A CSV reader of hvi's tables (`csv` crate: quoted cells, cells trimmed); rows of any length,
/// checked by [`read_numeric_csv`].
fn csv_reader(text: &str) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes())
}

/// The header of the CSV table `text` (read from the file `name`, which messages name).
fn read_csv_header(name: &str, text: &str) -> Result<Vec<String>, String> {
    let mut reader = csv_reader(text);
    let header = reader
        .headers()
        .map_err(|e| format!("{name}: cannot read the header: {e}"))?;
    Ok(header.iter().map(str::to_string).collect())
}

/// The header and the rows of the all-numeric CSV table `text` (read from the file `name`): a
/// row that is not valid CSV, has another length than the header or holds a cell that is not a
/// number is an error naming the file and the line.
fn read_numeric_csv(name: &str, text: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let header = read_csv_header(name, text)?;
    let mut reader = csv_reader(text);
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| match e.position() {
            Some(p) => format!("{name} line {}: {e}", p.line()),
            None => format!("{name}: {e}"),
        })?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() != header.len() {
            return Err(format!(
                "{name} line {line}: {} fields, but the header `{}` has {} columns",
                record.len(),
                header.join(","),
                header.len()
            ));
        }
        let row = record
            .iter()
            .zip(&header)
            .map(|(cell, column)| {
                cell.parse::<f64>()
                    .map_err(|_| format!("{name} line {line}: `{cell}` in column `{column}` is not a number"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        rows.push(row);
    }
    Ok((header, rows))
}

/// Reads `gamma3.csv` (`time,x,y,u_nu,force,pressure,status`) and places its nodes on the mesh;
/// a row that does not parse is an error naming its line.
pub fn read_gamma3(csv: &str, mesh: &Mesh<2>) -> Result<Gamma3, String> {
    let (header, rows) = read_numeric_csv("gamma3.csv", csv)?;
    let column = |name: &str| {
        header.iter().position(|c| *c == name).ok_or_else(|| {
            format!(
                "gamma3.csv has no `{name}` column (header `{}`; a 2D run writes `time,x,y,u_nu,force,pressure,status`)",
                header.join(",")
            )
        })
    };
    let cols = [
        column("time")?,
        column("x")?,
        column("y")?,
        column("u_nu")?,
        column("pressure")?,
    ];
    let mut times: Vec<(f64, Vec<(f64, f64)>)> = Vec::new();
    let mut positions: Vec<[f64; 2]> = Vec::new();
    for v in rows {
        let [t, x, y, un, p] = cols.map(|c| v[c]);
        if times.last().is_none_or(|(s, _)| *s != t) {
            times.push((t, Vec::new()));
        }
        if times.len() == 1 {
            positions.push([x, y]);
        }
        times.last_mut().expect("pushed above").1.push((un, p));
    }
    times.retain(|(_, rows)| rows.len() == positions.len());
    if positions.is_empty() || times.is_empty() {
        return Err("gamma3.csv has no complete time block: nothing to draw along Γ₃".into());
    }
    // the mesh node at each CSV position (the CSV prints coordinates to full precision)
    let (lo, hi) = bounding_box(&mesh.points);
    let tol = 1e-9 * ((hi[0] - lo[0]).abs() + (hi[1] - lo[1]).abs()).max(1e-300);
    let key = |p: [f64; 2]| ((p[0] / tol).round() as i64, (p[1] / tol).round() as i64);
    let by_position: HashMap<(i64, i64), usize> = mesh.points.iter().enumerate().map(|(i, &p)| (key(p), i)).collect();
    let nodes: Vec<usize> = positions
        .iter()
        .map(|&p| {
            by_position
                .get(&key(p))
                .copied()
                .or_else(|| {
                    (0..mesh.points.len())
                        .find(|&i| (mesh.points[i][0] - p[0]).abs() <= tol && (mesh.points[i][1] - p[1]).abs() <= tol)
                })
                .ok_or_else(|| {
                    format!(
                        "gamma3.csv names the point ({}, {}), which is no node of the mesh",
                        p[0], p[1]
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    let (arc, order, normals) = arc_length(mesh, &nodes);
    Ok(Gamma3 {
        nodes,
        normals,
        arc,
        order,
        times,
    })
}

/// Arc length along the curve through `nodes` (mesh nodes of a boundary part): the boundary
/// edges of the mesh joining two of them, chained from an end (the lowest, then leftmost,
/// end; any node of a closed curve), further pieces continuing the count. Returns each node's
/// arc length, the nodes' order along the curve and each node's outward unit normal (the
/// length-weighted mean of its edges' outward normals).
pub fn arc_length(mesh: &Mesh<2>, nodes: &[usize]) -> (Vec<f64>, Vec<usize>, Vec<[f64; 2]>) {
    let index: HashMap<usize, usize> = nodes.iter().enumerate().map(|(k, &p)| (p, k)).collect();
    // boundary edges (used by one cell), with the centroid of their cell for the outward side
    // (ordered: the normals' sums are added in the same order on every run)
    let mut edges: std::collections::BTreeMap<[usize; 2], (usize, [f64; 2])> = std::collections::BTreeMap::new();
    for c in &mesh.cells {
        let n = c.nodes();
        let centroid = n.iter().fold([0.0; 2], |a, &p| {
            [
                a[0] + mesh.points[p][0] / n.len() as f64,
                a[1] + mesh.points[p][1] / n.len() as f64,
            ]
        });
        for [a, b] in c.edges() {
            edges.entry([a.min(b), a.max(b)]).or_insert((0, centroid)).0 += 1;
        }
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    let mut normals = vec![[0.0; 2]; nodes.len()];
    for (&[a, b], &(count, centroid)) in &edges {
        if count != 1 {
            continue;
        }
        let (Some(&ka), Some(&kb)) = (index.get(&a), index.get(&b)) else {
            continue;
        };
        neighbours[ka].push(kb);
        neighbours[kb].push(ka);
        let (pa, pb) = (mesh.points[a], mesh.points[b]);
        let mut n = [pb[1] - pa[1], pa[0] - pb[0]]; // |n| = edge length
        let mid = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
        if (mid[0] - centroid[0]) * n[0] + (mid[1] - centroid[1]) * n[1] < 0.0 {
            n = [-n[0], -n[1]];
        }
        for k in [ka, kb] {
            normals[k][0] += n[0];
            normals[k][1] += n[1];
        }
    }
    for n in normals.iter_mut() {
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        if len > 0.0 {
            *n = [n[0] / len, n[1] / len];
        }
    }
    let p = |k: usize| mesh.points[nodes[k]];
    let lowest = |ks: &mut dyn Iterator<Item = usize>| {
        ks.min_by(|&a, &b| p(a)[1].total_cmp(&p(b)[1]).then(p(a)[0].total_cmp(&p(b)[0])))
    };
    let mut arc = vec![0.0; nodes.len()];
    let mut order = Vec::with_capacity(nodes.len());
    let mut seen = vec![false; nodes.len()];
    let mut s = 0.0;
    while order.len() < nodes.len() {
        let unseen = || (0..nodes.len()).filter(|&k| !seen[k]);
        let start = lowest(&mut unseen().filter(|&k| neighbours[k].len() <= 1))
            .or_else(|| lowest(&mut unseen()))
            .expect("an unseen node remains");
        let mut at = start;
        loop {
            seen[at] = true;
            arc[at] = s;
            order.push(at);
            let Some(&next) = neighbours[at].iter().find(|&&k| !seen[k]) else {
                break;
            };
            s += ((p(next)[0] - p(at)[0]).powi(2) + (p(next)[1] - p(at)[1]).powi(2)).sqrt();
            at = next;
        }
    }
    (arc, order, normals)
}

/// The deformed-mesh picture.
pub struct DeformedPicture<'a> {
    pub title: String,
    /// The colour bar's name.
    pub field: String,
    pub mesh: &'a Mesh<2>,
    pub displacement: &'a [[f64; 2]],
    pub cell_values: &'a [f64],
    pub scale: f64,
    /// The magnification as a sentence, drawn under the picture.
    pub scale_text: String,
    /// The foundation u_ν = g along Γ₃ (already magnified), drawn as a thick line.
    pub foundation: Option<Vec<[f64; 2]>>,
    /// The rigid obstacles' outlines (already magnified, [`magnify_from`]), drawn hatched.
    pub obstacles: Vec<ObstacleEdge>,
}

const PICTURE_WIDTH: u32 = 1200;
const TOP: i32 = 50;
const BOTTOM: i32 = 150;
const SIDE: i32 = 30;
const BAR: i32 = 400;

/// Draws the picture to a PNG and, if given, an SVG file.
pub fn render_deformed(png: &Path, svg: Option<&Path>, picture: &DeformedPicture) -> Result<(), String> {
    let mesh = picture.mesh;
    if picture.displacement.len() != mesh.points.len() || picture.cell_values.len() != mesh.cells.len() {
        return Err(format!(
            "deformed-mesh picture: {} nodal values for {} nodes, {} cell values for {} cells",
            picture.displacement.len(),
            mesh.points.len(),
            picture.cell_values.len(),
            mesh.cells.len()
        ));
    }
    let moved: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .zip(picture.displacement)
        .map(|(p, u)| [p[0] + picture.scale * u[0], p[1] + picture.scale * u[1]])
        .collect();
    let mut all: Vec<[f64; 2]> = mesh.points.iter().chain(&moved).copied().collect();
    all.extend(picture.foundation.iter().flatten());
    all.extend(picture.obstacles.iter().flat_map(|e| [e.a, e.b]));
    let (lo, hi) = bounding_box(&all);
    let span = [(hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300)];
    let px = ((PICTURE_WIDTH as i32 - 2 * SIDE) as f64 / span[0]).min(2400.0 / span[1]);
    let plot_h = (span[1] * px).ceil() as i32;
    let size = (PICTURE_WIDTH, (TOP + plot_h + BOTTOM) as u32);
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_deformed(&root, picture, &moved, lo, px, plot_h, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_deformed(&root, picture, &moved, lo, px, plot_h, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}

fn draw_deformed<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    picture: &DeformedPicture,
    moved: &[[f64; 2]],
    lo: [f64; 2],
    px: f64,
    plot_h: i32,
    lettering: Lettering,
) -> Result<(), String> {
    let mesh = picture.mesh;
    root.fill(&WHITE).map_err(err)?;
    let black = RGBColor(0, 0, 0);
    let grey = RGBColor(90, 90, 90);
    let to_px = |p: [f64; 2]| {
        (
            SIDE + ((p[0] - lo[0]) * px).round() as i32,
            TOP + plot_h - ((p[1] - lo[1]) * px).round() as i32,
        )
    };
    draw_text(root, lettering, &picture.title, (SIDE, 14), HPos::Left, 2, black)?;
    // colour range: the 2 % and 98 % quantiles, so that a few singular corner cells do not wash
    // out the rest (the bar says so)
    let mut sorted: Vec<f64> = picture.cell_values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let quantile = |q: f64| {
        sorted
            .get(((sorted.len().max(1) - 1) as f64 * q).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    let (vmin, vmax) = (quantile(0.02), quantile(0.98));
    let range = if vmax > vmin { vmax - vmin } else { 1.0 };
    // the undeformed outline (boundary edges), drawn in the edges' order: the same picture,
    // byte for byte, from the same run
    let mut edges: std::collections::BTreeMap<[usize; 2], usize> = std::collections::BTreeMap::new();
    for c in &mesh.cells {
        for [a, b] in c.edges() {
            *edges.entry([a.min(b), a.max(b)]).or_default() += 1;
        }
    }
    let light = RGBColor(170, 170, 170);
    for (&[a, b], _) in edges.iter().filter(|(_, &n)| n == 1) {
        root.draw(&PathElement::new(
            vec![to_px(mesh.points[a]), to_px(mesh.points[b])],
            light.stroke_width(2),
        ))
        .map_err(err)?;
    }
    let cell_px = mesh.cells.first().map_or(0.0, |c| {
        let n = c.nodes();
        let (a, b) = (mesh.points[n[0]], mesh.points[n[1]]);
        ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt() * px
    });
    let edge_colour = RGBColor(30, 30, 30).mix(0.35);
    for (c, v) in mesh.cells.iter().zip(picture.cell_values) {
        let poly: Vec<(i32, i32)> = c.nodes().iter().map(|&p| to_px(moved[p])).collect();
        let colour = colour_map((v - vmin) / range);
        root.draw(&Polygon::new(poly.clone(), colour.filled())).map_err(err)?;
        let mut closed = poly;
        closed.push(closed[0]);
        let stroke = if cell_px >= 8.0 {
            edge_colour.stroke_width(1)
        } else {
            colour.stroke_width(1)
        };
        root.draw(&PathElement::new(closed, stroke)).map_err(err)?;
    }
    let mut y = TOP + plot_h + 16;
    if let Some(f) = &picture.foundation {
        let line: Vec<(i32, i32)> = f.iter().map(|&q| to_px(q)).collect();
        root.draw(&PathElement::new(line, RGBColor(150, 40, 40).stroke_width(4)))
            .map_err(err)?;
    }
    // the obstacles: their outline, with a tick into the obstacle every HATCH pixels
    const HATCH: f64 = 12.0;
    let dark = RGBColor(40, 40, 40);
    let mut along = 0.0;
    let mut last_end = None;
    for e in &picture.obstacles {
        let (a, b) = (to_px(e.a), to_px(e.b));
        if last_end != Some(a) {
            along = 0.0; // a new curve
        }
        last_end = Some(b);
        root.draw(&PathElement::new(vec![a, b], dark.stroke_width(3)))
            .map_err(err)?;
        let len = (((b.0 - a.0) as f64).powi(2) + ((b.1 - a.1) as f64).powi(2)).sqrt();
        let mut s = HATCH - along;
        while s <= len {
            let t = if len > 0.0 { s / len } else { 0.0 };
            let p = (a.0 as f64 + t * (b.0 - a.0) as f64, a.1 as f64 + t * (b.1 - a.1) as f64);
            // pixel y grows downwards
            let q = (p.0 + 8.0 * e.inward[0], p.1 - 8.0 * e.inward[1]);
            root.draw(&PathElement::new(
                vec![
                    (p.0.round() as i32, p.1.round() as i32),
                    (q.0.round() as i32, q.1.round() as i32),
                ],
                dark.stroke_width(1),
            ))
            .map_err(err)?;
            s += HATCH;
        }
        along = (along + len) % HATCH;
    }
    // the colour bar: the field's name, min and max
    let bar_y = y + 20;
    draw_text(
        root,
        lettering,
        &format!("{} (colours span the 2-98 % quantiles of the cells)", picture.field),
        (SIDE, y),
        HPos::Left,
        2,
        black,
    )?;
    for i in 0..BAR {
        let colour = colour_map(i as f64 / (BAR - 1) as f64);
        root.draw(&Rectangle::new(
            [(SIDE + i, bar_y), (SIDE + i + 1, bar_y + 16)],
            colour.filled(),
        ))
        .map_err(err)?;
    }
    root.draw(&Rectangle::new(
        [(SIDE, bar_y), (SIDE + BAR, bar_y + 16)],
        grey.stroke_width(1),
    ))
    .map_err(err)?;
    draw_text(
        root,
        lettering,
        &sci_text(vmin),
        (SIDE, bar_y + 22),
        HPos::Left,
        2,
        black,
    )?;
    draw_text(
        root,
        lettering,
        &sci_text(vmax),
        (SIDE + BAR, bar_y + 22),
        HPos::Right,
        2,
        black,
    )?;
    y = bar_y + 48;
    let mut legend = vec![picture.scale_text.clone(), "grey: the undeformed outline".to_string()];
    if picture.foundation.is_some() {
        legend.push("red: the foundation u_ν = g (same magnification)".into());
    }
    if !picture.obstacles.is_empty() {
        legend.push(if picture.scale == 1.0 {
            "black, hatched: the obstacle".to_string()
        } else {
            "black, hatched: the obstacle, its distance from Γ₃ magnified like the displacement".to_string()
        });
    }
    for line in legend {
        draw_text(root, lettering, &line, (SIDE, y), HPos::Left, 2, black)?;
        y += 20;
    }
    Ok(())
}

/// The Γ₃ figure: u_ν and the pressure against arc length at several times.
pub struct Gamma3Figure {
    pub title: String,
    pub x_label: String,
    /// Arc length of the nodes, in order along Γ₃.
    pub arc: Vec<f64>,
    /// The bound g at the nodes, if any.
    pub bound: Option<Vec<f64>>,
    /// (t, u_ν, pressure) at the nodes, per time.
    pub curves: Vec<(f64, Vec<f64>, Vec<f64>)>,
}

const FIG_W: i32 = 1100;
const PANEL_H: i32 = 300;
const LEFT: i32 = 120;
const RIGHT: i32 = 170;

/// Draws the figure (two panels, a legend of the times) to a PNG and, if given, an SVG file.
pub fn render_gamma3(png: &Path, svg: Option<&Path>, figure: &Gamma3Figure) -> Result<(), String> {
    if figure.curves.is_empty() || figure.arc.is_empty() {
        return Err("Γ₃ plot: no time or no node to draw".into());
    }
    let size = (FIG_W as u32, (60 + 2 * (PANEL_H + 80)) as u32);
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_gamma3(&root, figure, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_gamma3(&root, figure, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}

fn time_colour(i: usize, n: usize) -> RGBColor {
    colour_map(if n > 1 { 0.9 * i as f64 / (n - 1) as f64 } else { 0.0 })
}

fn draw_gamma3<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    figure: &Gamma3Figure,
    lettering: Lettering,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let black = RGBColor(0, 0, 0);
    let grey = RGBColor(90, 90, 90);
    draw_text(root, lettering, &figure.title, (20, 14), HPos::Left, 2, black)?;
    let (s0, s1) = figure
        .arc
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &s| (a.min(s), b.max(s)));
    let s1 = if s1 > s0 { s1 } else { s0 + 1.0 };
    let pw = FIG_W - LEFT - RIGHT;
    let n = figure.curves.len();
    // panel 0: u_ν, panel 1: the pressure
    type Curve = (f64, Vec<f64>, Vec<f64>);
    type Values = fn(&Curve) -> &Vec<f64>;
    fn u_nu(c: &Curve) -> &Vec<f64> {
        &c.1
    }
    fn pressure(c: &Curve) -> &Vec<f64> {
        &c.2
    }
    let panels: [(&str, Values); 2] = [("normal displacement u_ν", u_nu), ("contact pressure", pressure)];
    for (k, (name, values)) in panels.iter().enumerate() {
        let top = 60 + k as i32 * (PANEL_H + 80);
        let mut all: Vec<f64> = figure.curves.iter().flat_map(|c| values(c).iter().copied()).collect();
        if k == 0 {
            all.extend(figure.bound.iter().flatten());
        }
        let (mut v0, mut v1) = field_range(&all);
        v0 = v0.min(0.0);
        v1 = v1.max(0.0);
        if v1 <= v0 {
            v1 = v0 + 1.0;
        }
        let pad = 0.05 * (v1 - v0);
        let (v0, v1) = (v0 - pad, v1 + pad);
        let to_px = |s: f64, v: f64| {
            (
                LEFT + ((s - s0) / (s1 - s0) * pw as f64).round() as i32,
                top + PANEL_H - ((v - v0) / (v1 - v0) * PANEL_H as f64).round() as i32,
            )
        };
        root.draw(&Rectangle::new(
            [(LEFT, top), (LEFT + pw, top + PANEL_H)],
            grey.stroke_width(1),
        ))
        .map_err(err)?;
        draw_text(root, lettering, name, (LEFT, top - 22), HPos::Left, 2, black)?;
        let (xt, xstep) = linear_ticks(s0, s1, 8);
        let xt: Vec<(i32, f64)> = xt.into_iter().map(|v| (to_px(v, v0).0, v)).collect();
        draw_x_ticks(root, lettering, &xt, xstep, top + PANEL_H, grey, black)?;
        let (yt, ystep) = linear_ticks(v0, v1, 5);
        for v in yt {
            let (_, y) = to_px(s0, v);
            root.draw(&PathElement::new(
                vec![(LEFT, y), (LEFT + pw, y)],
                RGBColor(235, 235, 235).stroke_width(1),
            ))
            .map_err(err)?;
            draw_text(
                root,
                lettering,
                &tick_label(v, ystep),
                (LEFT - 8, y - 7),
                HPos::Right,
                2,
                black,
            )?;
        }
        draw_text(
            root,
            lettering,
            &figure.x_label,
            (LEFT + pw / 2, top + PANEL_H + 32),
            HPos::Center,
            2,
            black,
        )?;
        if let (0, Some(g)) = (k, &figure.bound) {
            let line: Vec<(i32, i32)> = figure.arc.iter().zip(g).map(|(&s, &v)| to_px(s, v)).collect();
            root.draw(&PathElement::new(line, RGBColor(150, 40, 40).stroke_width(2)))
                .map_err(err)?;
        }
        for (i, c) in figure.curves.iter().enumerate() {
            let line: Vec<(i32, i32)> = figure.arc.iter().zip(values(c)).map(|(&s, &v)| to_px(s, v)).collect();
            root.draw(&PathElement::new(line, time_colour(i, n).stroke_width(2)))
                .map_err(err)?;
        }
        // the legend: one entry per time (and the bound)
        let lx = LEFT + pw + 16;
        let mut ly = top + 4;
        if let (0, Some(_)) = (k, &figure.bound) {
            root.draw(&PathElement::new(
                vec![(lx, ly + 7), (lx + 24, ly + 7)],
                RGBColor(150, 40, 40).stroke_width(2),
            ))
            .map_err(err)?;
            draw_text(root, lettering, "bound g", (lx + 30, ly), HPos::Left, 2, black)?;
            ly += 20;
        }
        for (i, c) in figure.curves.iter().enumerate() {
            root.draw(&PathElement::new(
                vec![(lx, ly + 7), (lx + 24, ly + 7)],
                time_colour(i, n).stroke_width(3),
            ))
            .map_err(err)?;
            draw_text(
                root,
                lettering,
                &format!("t = {}", sci_text(c.0)),
                (lx + 30, ly),
                HPos::Left,
                2,
                black,
            )?;
            ly += 20;
        }
    }
    Ok(())
}

/// `hvi plot` of a 3D run: u_ν and the contact pressure over Γ₃ at the last time of
/// `gamma3.csv`, as two colour maps of the nodes projected onto the plane of the two coordinates
/// with the largest spread (Γ₃ is flat in the shipped examples), nodes on the bound outlined.
fn plot_3d(run_dir: &Path, last: &str) -> Result<Vec<PathBuf>, SolveError> {
    use surface::{project_surface, render_surface_map, MapPanel, SurfaceMap};
    let fail = |what: String| SolveError::Setup(format!("{}: {what}", run_dir.display()));
    let csv = std::fs::read_to_string(run_dir.join("gamma3.csv")).map_err(|e| {
        fail(format!(
            "{last} is a 3D run, drawn by hvi plot from gamma3.csv, which cannot be read ({e}; a run without \
             contact output has none): open solution.pvd in ParaView (Warp By Vector on displacement, colour \
             by von_mises)"
        ))
    })?;
    let (header, table) = read_numeric_csv("gamma3.csv", &csv).map_err(fail)?;
    let column = |name: &str| {
        header.iter().position(|c| *c == name).ok_or_else(|| {
            fail(format!(
                "gamma3.csv has no `{name}` column (header `{}`, a 3D run writes \
                 `time,x,y,z,u_nu,force,pressure,status`)",
                header.join(",")
            ))
        })
    };
    let cols = [
        column("time")?,
        column("x")?,
        column("y")?,
        column("z")?,
        column("u_nu")?,
        column("pressure")?,
        column("status")?,
    ];
    // the rows of the last time (rows are written time by time)
    let mut rows: Vec<[f64; 7]> = Vec::new();
    for v in table {
        let row = cols.map(|c| v[c]);
        if rows.first().is_some_and(|r| r[0] != row[0]) {
            rows.clear();
        }
        rows.push(row);
    }
    let Some(time) = rows.first().map(|r| r[0]) else {
        return Err(fail("gamma3.csv has no row: nothing to draw".into()));
    };
    let points: Vec<[f64; 3]> = rows.iter().map(|r| [r[1], r[2], r[3]]).collect();
    let (axes, projected) = project_surface(&points);
    let t = sci(time);
    let map = SurfaceMap {
        axes: axes.map(|a| ["x", "y", "z"][a].to_string()),
        points: projected,
        marked: rows.iter().map(|r| r[6] == 2.0).collect(),
        marked_meaning: "outlined: nodes on the bound".into(),
        panels: vec![
            MapPanel {
                title: format!("Normal displacement u_ν on Γ₃ at t = {t}"),
                name: format!("u_ν at t = {t}"),
                values: rows.iter().map(|r| r[4]).collect(),
            },
            MapPanel {
                title: format!("Contact pressure on Γ₃ at t = {t}"),
                name: format!("pressure at t = {t}"),
                values: rows.iter().map(|r| r[5]).collect(),
            },
        ],
    };
    let (png, svg) = pictures(run_dir, "gamma3_map")?;
    render_surface_map(&png, Some(&svg), &map).map_err(fail)?;
    Ok(vec![png, svg])
}

/// A piece of an obstacle's outline in the deformed picture (docs/method.md §12.4): a segment
/// and the unit direction from it into the obstacle (where φ < 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleEdge {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub inward: [f64; 2],
}

/// The zero level set of φ over the box `lo`–`hi` by marching squares on an `nx` × `ny` grid
/// (the crossing on each grid edge by linear interpolation, a saddle resolved by the value at
/// the cell's centre), each segment with the direction −∇φ/|∇φ| at its midpoint (central
/// differences of a tenth of a grid cell). Exact for a plane; for a circle of radius R the
/// vertices lie within about h²/(8R) of it, h the grid spacing.
pub fn level_set_segments(
    phi: &dyn Fn([f64; 2]) -> f64,
    lo: [f64; 2],
    hi: [f64; 2],
    nx: usize,
    ny: usize,
) -> Vec<ObstacleEdge> {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let d = [(hi[0] - lo[0]) / nx as f64, (hi[1] - lo[1]) / ny as f64];
    let at = |i: usize, j: usize| [lo[0] + i as f64 * d[0], lo[1] + j as f64 * d[1]];
    let values: Vec<f64> = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| (i, j)))
        .map(|(i, j)| phi(at(i, j)))
        .collect();
    let v = |i: usize, j: usize| values[j * (nx + 1) + i];
    let cross = |p: [f64; 2], q: [f64; 2], a: f64, b: f64| {
        let t = if a == b { 0.5 } else { a / (a - b) };
        [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
    };
    let step = 0.1 * d[0].abs().min(d[1].abs());
    let inward = |m: [f64; 2]| {
        let g = [
            phi([m[0] + step, m[1]]) - phi([m[0] - step, m[1]]),
            phi([m[0], m[1] + step]) - phi([m[0], m[1] - step]),
        ];
        let n = (g[0] * g[0] + g[1] * g[1]).sqrt();
        if n > 0.0 && n.is_finite() {
            [-g[0] / n, -g[1] / n]
        } else {
            [0.0, 0.0]
        }
    };
    let mut edges = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let corner = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let val = corner.map(|(a, b)| v(a, b));
            if val.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let inside = val.map(|x| x < 0.0);
            // the crossings on the edges bottom, right, top, left (corner k to k + 1)
            let crossings: Vec<(usize, [f64; 2])> = (0..4)
                .filter(|&k| inside[k] != inside[(k + 1) % 4])
                .map(|k| {
                    // from the corner of lower (j, i) to the other, as the neighbouring cell
                    // does too: both compute the same point, bit for bit
                    let (mut p, mut q, mut vp, mut vq) = (corner[k], corner[(k + 1) % 4], val[k], val[(k + 1) % 4]);
                    if (q.1, q.0) < (p.1, p.0) {
                        std::mem::swap(&mut p, &mut q);
                        std::mem::swap(&mut vp, &mut vq);
                    }
                    (k, cross(at(p.0, p.1), at(q.0, q.1), vp, vq))
                })
                .collect();
            let pairs: Vec<([f64; 2], [f64; 2])> = match crossings.len() {
                2 => vec![(crossings[0].1, crossings[1].1)],
                4 => {
                    let centre = phi([at(i, j)[0] + 0.5 * d[0], at(i, j)[1] + 0.5 * d[1]]);
                    let c = |k: usize| crossings[k].1;
                    if (centre < 0.0) == inside[0] {
                        // corners 0 and 2 joined through the centre: cut off corners 1 and 3
                        vec![(c(0), c(1)), (c(2), c(3))]
                    } else {
                        vec![(c(3), c(0)), (c(1), c(2))]
                    }
                }
                _ => vec![],
            };
            for (a, b) in pairs {
                let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                edges.push(ObstacleEdge {
                    a,
                    b,
                    inward: inward(m),
                });
            }
        }
    }
    // a grid vertex exactly on the curve (φ = 0) makes a segment of no length in a cell
    // touching it: dropped, the curve runs through the vertex in the neighbouring cells
    let tol = 1e-9 * d[0].abs().max(d[1].abs());
    edges.retain(|e| (e.a[0] - e.b[0]).abs().max((e.a[1] - e.b[1]).abs()) > tol);
    chain(edges, tol)
}

/// The edges reordered (and turned) so that each next one starts where the previous one ended,
/// curve by curve (open curves from an end): the hatching then runs at an even pitch along each
/// curve. Ends closer than `tol` are one point (a grid edge's crossing is computed in both cells
/// that share it).
fn chain(edges: Vec<ObstacleEdge>, tol: f64) -> Vec<ObstacleEdge> {
    let key = |p: [f64; 2]| ((p[0] / tol).round() as i64, (p[1] / tol).round() as i64);
    let mut at: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, e) in edges.iter().enumerate() {
        at.entry(key(e.a)).or_default().push(i);
        at.entry(key(e.b)).or_default().push(i);
    }
    let degree = |p: [f64; 2]| at.get(&key(p)).map_or(0, Vec::len);
    let n = edges.len();
    let starts: Vec<usize> = (0..n)
        .filter(|&i| degree(edges[i].a) == 1 || degree(edges[i].b) == 1)
        .chain(0..n)
        .collect();
    let mut used = vec![false; n];
    let mut out = Vec::with_capacity(n);
    for start in starts {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut e = edges[start];
        if degree(e.b) == 1 && degree(e.a) != 1 {
            std::mem::swap(&mut e.a, &mut e.b);
        }
        loop {
            out.push(e);
            let end = e.b;
            let Some(j) = at.get(&key(end)).and_then(|v| v.iter().copied().find(|&j| !used[j])) else {
                break;
            };
            used[j] = true;
            e = edges[j];
            if key(e.a) != key(end) {
                std::mem::swap(&mut e.a, &mut e.b);
            }
        }
    }
    out
}

/// The outline moved into a picture whose displacements are magnified by `scale`: each point y
/// goes to f + scale·(y − f), f the closest point of the undeformed Γ₃ (`gamma3`, its segments),
/// so that distances from Γ₃ are magnified like the displacement and a node resting on the
/// obstacle is drawn on it (docs/method.md §12.4). Unchanged at scale 1 or without Γ₃.
pub fn magnify_from(edges: &mut [ObstacleEdge], gamma3: &[[[f64; 2]; 2]], scale: f64) {
    if scale == 1.0 || gamma3.is_empty() {
        return;
    }
    let closest = |y: [f64; 2]| {
        gamma3
            .iter()
            .map(|[p, q]| {
                let e = [q[0] - p[0], q[1] - p[1]];
                let ee = e[0] * e[0] + e[1] * e[1];
                let t = if ee > 0.0 {
                    (((y[0] - p[0]) * e[0] + (y[1] - p[1]) * e[1]) / ee).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let f = [p[0] + t * e[0], p[1] + t * e[1]];
                ((y[0] - f[0]).powi(2) + (y[1] - f[1]).powi(2), f)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, f)| f)
            .expect("Γ₃ has a segment")
    };
    let map = |y: [f64; 2]| {
        let f = closest(y);
        [f[0] + scale * (y[0] - f[0]), f[1] + scale * (y[1] - f[1])]
    };
    for e in edges.iter_mut() {
        e.a = map(e.a);
        e.b = map(e.b);
    }
}
