//! `hvi plot RUN_DIR` (docs/outputs.md "Pictures without ParaView"): what the run directory holds decides the pictures, their
//! times and their magnification.

use super::error::PlotError;
use crate::mesh::{Cell, CellKind, Mesh};
use crate::output;
use crate::plot::deformed::cell_colours;
use crate::plot::deformed::render_deformed;
use crate::plot::deformed::DeformedPicture;
use crate::plot::gamma3::render_gamma3;
use crate::plot::gamma3::Gamma3Figure;
use crate::plot::kit::bounding_box;
use crate::plot::kit::sci_text;
use crate::plot::obstacle::obstacle_edges;
use crate::plot::read::read_csv_header;
use crate::plot::read::read_numeric_csv;
use crate::plot::read_gamma3;
use crate::plot::sci;
use crate::scene::Scene;
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
pub(super) const VISIBLE_FRACTION: f64 = 0.05;

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
pub fn plot_run(run_dir: &Path, options: &PlotOptions) -> Result<Vec<PathBuf>, PlotError> {
    let fail = |detail: String| PlotError::Run {
        dir: run_dir.to_path_buf(),
        detail,
    };
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
            // VTK's quadratic triangle and quadrangles list their nodes in gmsh's order
            6 => Ok(Cell::new(CellKind::Tri6, c)),
            8 => Ok(Cell::new(CellKind::Quad8, c)),
            9 => Ok(Cell::new(CellKind::Quad9, c)),
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
        (Some(spec), Some(g3)) => Some(
            crate::solver::bound::nodal_bound(spec, &g3.nodes, &mesh.points, "scene.toml", "contact.bound")
                .map_err(|e| PlotError::Scene(e.to_string()))?,
        ),
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
            None => {
                let spread = evenly_spaced(&available, 6);
                let positive: Vec<f64> = available.iter().copied().filter(|&t| t > 0.0).collect();
                let log =
                    positive.len() > 6 && positive[positive.len() - 1] / positive[0] >= super::history::LOG_AXIS_FROM;
                let why = if log {
                    "output times spread in log t"
                } else {
                    "evenly spaced output times"
                };
                (spread, why.to_string())
            }
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
            zones: chosen
                .last()
                .and_then(|&i| g3.friction.get(i))
                .map(|codes| g3.order.iter().map(|&k| codes[k]).collect()),
        };
        let (png, svg) = pictures(run_dir, "gamma3")?;
        render_gamma3(&png, Some(&svg), &figure).map_err(fail)?;
        written.extend([png, svg]);
        // the largest u_ν over time: an indentation's depth, a creep curve
        if g3.times.len() >= 3 {
            let history = super::history::HistoryFigure {
                title: format!("{name}: the largest u_ν on Γ₃ at every output time"),
                y_label: "largest normal displacement u_ν on Γ₃".into(),
                points: g3
                    .times
                    .iter()
                    .map(|(t, rows)| (*t, rows.iter().map(|r| r.0).fold(f64::NEG_INFINITY, f64::max)))
                    .collect(),
            };
            let (png, svg) = pictures(run_dir, "history")?;
            super::history::render_history(&png, Some(&svg), &history).map_err(fail)?;
            written.extend([png, svg]);
        }
        // with friction: the zones at every output time (docs/method.md §17.5)
        if g3.friction.len() == g3.times.len() && !g3.friction.is_empty() {
            let zones = super::zones::ZonesFigure {
                title: format!("{name}: stick and slip along Γ₃ over time"),
                x_label: figure.x_label.clone(),
                arc: figure.arc.clone(),
                times: g3
                    .times
                    .iter()
                    .zip(&g3.friction)
                    .map(|((t, _), codes)| (*t, g3.order.iter().map(|&k| codes[k]).collect()))
                    .collect(),
            };
            let (png, svg) = pictures(run_dir, "gamma3_zones")?;
            super::zones::render_zones(&png, Some(&svg), &zones).map_err(fail)?;
            written.extend([png, svg]);
        }
    }
    Ok(written)
}

/// The PNG and SVG files of picture `stem` in the run directory, recorded in the run's manifest
/// before they are written, so that `hvi solve --overwrite` removes them with the run's own files
/// (docs/method.md §12.2).
pub(super) fn pictures(run_dir: &Path, stem: &str) -> Result<(PathBuf, PathBuf), PlotError> {
    let (png, svg) = (format!("{stem}.png"), format!("{stem}.svg"));
    output::record_in_run(run_dir, &[&png, &svg])?;
    Ok((run_dir.join(png), run_dir.join(svg)))
}

/// The run's name for titles: its directory, with the mesh from summary.json when there is one.
pub(super) fn run_name(run_dir: &Path) -> String {
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
pub(super) fn is_paper_scene(scene: &Scene) -> bool {
    let Ok(mut paper) = Scene::load(None, &[]) else {
        return false;
    };
    paper.time.steps = scene.time.steps;
    paper.output = scene.output.clone();
    paper.to_toml_string() == scene.to_toml_string()
}

/// Up to `count` of the times (t = 0, the unloaded start, left out when there are others),
/// evenly spaced by index, always including the last; spread evenly in log t when they span
/// decades (steps growing with time, docs/method.md §20), so that early times are drawn too.
pub(super) fn evenly_spaced(times: &[f64], count: usize) -> Vec<f64> {
    let later: Vec<f64> = times.iter().copied().filter(|t| *t != 0.0).collect();
    let later = if later.is_empty() { times.to_vec() } else { later };
    if later.len() <= count {
        return later;
    }
    let (first, last) = (later[0], later[later.len() - 1]);
    if first > 0.0 && last / first >= super::history::LOG_AXIS_FROM {
        return (0..count)
            .map(|i| first * (last / first).powf(i as f64 / (count - 1) as f64))
            .collect();
    }
    (1..=count)
        .map(|i| later[(i * later.len()).div_ceil(count) - 1])
        .collect()
}

/// Indices of the available times nearest to each wanted time, without repeats, in time order.
pub(super) fn nearest_times(available: &[f64], wanted: &[f64]) -> Vec<usize> {
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

/// `hvi plot` of a 3D run: u_ν and the contact pressure over Γ₃ at the last time of
/// `gamma3.csv`, as two colour maps of the nodes projected onto the plane of the two coordinates
/// with the largest spread (Γ₃ is flat in the shipped examples), nodes on the bound outlined.
pub(super) fn plot_3d(run_dir: &Path, last: &str) -> Result<Vec<PathBuf>, PlotError> {
    use super::surface::{project_surface, render_surface_map, MapPanel, SurfaceMap};
    let fail = |detail: String| PlotError::Run {
        dir: run_dir.to_path_buf(),
        detail,
    };
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
    // a run with friction: its status column (docs/method.md §17.5)
    let friction = header.iter().position(|c| *c == "friction_status");
    // the rows of the last time (rows are written time by time)
    let mut rows: Vec<[f64; 8]> = Vec::new();
    for v in table {
        let picked = cols.map(|c| v[c]);
        let mut row = [0.0; 8];
        row[..7].copy_from_slice(&picked);
        row[7] = friction.map_or(-1.0, |c| v[c]);
        if rows.first().is_some_and(|r| r[0] != row[0]) {
            rows.clear();
        }
        rows.push(row);
    }
    let Some(time) = rows.first().map(|r| r[0]) else {
        return Err(fail("gamma3.csv has no row: nothing to draw".into()));
    };
    // the surface's own faces from the contact frame of that time, else the rows' node tiles
    let surface = contact_surface(run_dir, time).unwrap_or_else(|| ContactSurface {
        points: rows.iter().map(|r| [r[1], r[2], r[3]]).collect(),
        faces: Vec::new(),
        u_nu: rows.iter().map(|r| r[4]).collect(),
        pressure: rows.iter().map(|r| r[5]).collect(),
        status: rows.iter().map(|r| r[6]).collect(),
        friction: friction.map(|_| rows.iter().map(|r| r[7]).collect()),
    });
    let (axes, projected) = project_surface(&surface.points);
    let t = sci(time);
    let by_faces = !surface.faces.is_empty();
    let mut map = SurfaceMap {
        faces: surface.faces,
        axes: axes.map(|a| ["x", "y", "z"][a].to_string()),
        points: projected,
        marked: surface.status.iter().map(|&s| s == 2.0).collect(),
        marked_meaning: if by_faces {
            "squares: nodes on the bound".into()
        } else {
            "outlined: nodes on the bound".into()
        },
        panels: vec![
            MapPanel {
                title: format!("Normal displacement u_ν on Γ₃ at t = {t}"),
                name: format!("u_ν at t = {t}"),
                values: surface.u_nu,
                zones: false,
            },
            MapPanel {
                title: format!("Contact pressure on Γ₃ at t = {t}"),
                name: format!("pressure at t = {t}"),
                values: surface.pressure,
                zones: false,
            },
        ],
    };
    // with friction, a third panel: the stick and slip zones (docs/method.md §17.5)
    if let Some(zones) = surface.friction {
        map.panels.push(MapPanel {
            title: format!("Stick and slip on Γ₃ at t = {t}"),
            name: "friction status".into(),
            values: zones,
            zones: true,
        });
    }
    let (png, svg) = pictures(run_dir, "gamma3_map")?;
    render_surface_map(&png, Some(&svg), &map).map_err(fail)?;
    Ok(vec![png, svg])
}

/// Γ₃ as the run's last contact frame has it (`contact.pvd`'s last `.vtp`): its points, faces,
/// u_ν, pressure and status (every node of the surface, also those whose normal is prescribed),
/// at `time` (the last time of gamma3.csv). None when there is no such frame (the map then draws
/// node tiles of gamma3.csv's rows).
struct ContactSurface {
    points: Vec<[f64; 3]>,
    faces: Vec<Vec<usize>>,
    u_nu: Vec<f64>,
    pressure: Vec<f64>,
    status: Vec<f64>,
    /// The friction status codes (a run with friction; −1 where a node has none).
    friction: Option<Vec<f64>>,
}

fn contact_surface(run_dir: &Path, time: f64) -> Option<ContactSurface> {
    let frames = output::read_pvd(&run_dir.join("contact.pvd")).ok()?;
    let (t, last) = frames.last()?;
    if (t - time).abs() > 1e-12 * time.abs().max(1.0) {
        return None;
    }
    let frame = output::read_vtu_arrays(&run_dir.join(last)).ok()?;
    let field = |name: &str| {
        frame
            .point_data
            .get(name)
            .filter(|(k, v)| *k == 1 && v.len() == frame.points.len())
            .map(|(_, v)| v.clone())
    };
    let faces: Vec<Vec<usize>> = frame
        .connectivity
        .iter()
        .filter(|c| (3..=4).contains(&c.len()) && c.iter().all(|&n| n < frame.points.len()))
        .cloned()
        .collect();
    if faces.is_empty() {
        return None;
    }
    Some(ContactSurface {
        u_nu: field("u_nu")?,
        pressure: field("pressure")?,
        status: field("status")?,
        friction: field("friction_status"),
        points: frame.points,
        faces,
    })
}
