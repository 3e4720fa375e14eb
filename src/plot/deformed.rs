//! The deformed picture of a 2D run (docs/method.md §12.3): the last frame's mesh moved by the
//! magnified displacement, coloured by the active scalar, with its colour bar and the obstacles.

use super::kit::{draw_text, err, Lettering};
use crate::mesh::{Cell, Mesh};
use crate::output;
use crate::plot::colour_map;
use crate::plot::kit::bounding_box;
use crate::plot::kit::sci_text;
use crate::plot::obstacle::ObstacleEdge;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::path::Path;

/// The colour of each cell and the colour bar's name: the run's active scalar
/// (`output.active_scalar`, docs/method.md §12.3) — von Mises from the cells' values, the stress
/// by its Frobenius norm |σ| (ParaView's magnitude of the tensor), the displacement by |u| (the
/// mean over the cell's nodes) — falling back to |u| when the run has not written the field.
pub(super) fn cell_colours(
    active: &str,
    vtu: &output::VtuContents,
    cells: &[Cell],
    u: &[[f64; 2]],
) -> (String, Vec<f64>) {
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

pub(super) const PICTURE_WIDTH: u32 = 1200;

pub(super) const TOP: i32 = 50;

pub(super) const BOTTOM: i32 = 150;

pub(super) const SIDE: i32 = 30;

pub(super) const BAR: i32 = 400;

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

pub(super) fn draw_deformed<DB: DrawingBackend>(
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
        // a second-order cell is drawn by its corners (straight edges)
        let poly: Vec<(i32, i32)> = c.corners().iter().map(|&p| to_px(moved[p])).collect();
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
