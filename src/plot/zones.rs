//! The friction zones of a 2D run over time (docs/method.md §17.5): `gamma3_zones.png`/`.svg`,
//! arc length along Γ₃ across, time up, each node's cell from midpoint to midpoint coloured by
//! its friction status at each output time (stick green, slip orange, separated grey).

use super::kit::{
    draw_text, draw_x_ticks, draw_y_ticks, draw_zone_legend, err, linear_ticks, zone_colour, Lettering, SEPARATED,
};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::path::Path;

/// The zones figure: the friction status of each node (in order along Γ₃) at each output time.
pub struct ZonesFigure {
    pub title: String,
    pub x_label: String,
    /// Arc length of the nodes, in order along Γ₃.
    pub arc: Vec<f64>,
    /// (t, the status codes of the nodes in `arc`'s order), per output time, in time order.
    pub times: Vec<(f64, Vec<i32>)>,
}

const WIDTH: i32 = 1100;
const HEIGHT: i32 = 560;
const LEFT: i32 = 120;
const RIGHT: i32 = 40;
const TOP: i32 = 50;
const BOTTOM: i32 = 120;

/// The colour of a status code: stick, slip, separated (light grey), none (white).
fn colour(code: i32) -> RGBColor {
    zone_colour(code).unwrap_or(if code == 0 { SEPARATED } else { WHITE })
}

/// Draws the figure to a PNG and, if given, an SVG file.
pub fn render_zones(png: &Path, svg: Option<&Path>, figure: &ZonesFigure) -> Result<(), String> {
    if figure.times.is_empty() || figure.arc.is_empty() {
        return Err("zones plot: no time or no node to draw".into());
    }
    if let Some((t, codes)) = figure.times.iter().find(|(_, c)| c.len() != figure.arc.len()) {
        return Err(format!(
            "zones plot: {} codes at t = {t} for {} nodes",
            codes.len(),
            figure.arc.len()
        ));
    }
    let size = (WIDTH as u32, HEIGHT as u32);
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_zones(&root, figure, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_zones(&root, figure, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}

fn draw_zones<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    figure: &ZonesFigure,
    lettering: Lettering,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let (black, grey) = (RGBColor(0, 0, 0), RGBColor(90, 90, 90));
    draw_text(root, lettering, &figure.title, (20, 14), HPos::Left, 2, black)?;
    let (pw, ph) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
    let arc = &figure.arc;
    let n = arc.len();
    // each node's cell: from the midpoint to its left neighbour to the midpoint to its right one
    let edge = |i: usize| -> f64 {
        match i {
            0 => arc[0],
            _ if i == n => arc[n - 1],
            _ => 0.5 * (arc[i - 1] + arc[i]),
        }
    };
    let (s0, s1) = (arc[0], if arc[n - 1] > arc[0] { arc[n - 1] } else { arc[0] + 1.0 });
    let times: Vec<f64> = figure.times.iter().map(|(t, _)| *t).collect();
    let (t0, t1) = (times[0], *times.last().expect("a time"));
    let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
    // each time's band: from the midpoint to the previous output time to the one to the next
    let band = |k: usize| -> f64 {
        match k {
            0 => t0,
            _ if k == times.len() => t1,
            _ => 0.5 * (times[k - 1] + times[k]),
        }
    };
    let x_px = |s: f64| LEFT + ((s - s0) / (s1 - s0) * pw as f64).round() as i32;
    let y_px = |t: f64| TOP + ph - ((t - t0) / (t1 - t0) * ph as f64).round() as i32;
    for (k, (_, codes)) in figure.times.iter().enumerate() {
        let (top, bottom) = (y_px(band(k + 1)), y_px(band(k)));
        for (i, &code) in codes.iter().enumerate() {
            let (left, right) = (x_px(edge(i)), x_px(edge(i + 1)));
            root.draw(&Rectangle::new(
                [(left, top), (right.max(left + 1), bottom.max(top + 1))],
                colour(code).filled(),
            ))
            .map_err(err)?;
        }
    }
    root.draw(&Rectangle::new(
        [(LEFT, TOP), (LEFT + pw, TOP + ph)],
        grey.stroke_width(1),
    ))
    .map_err(err)?;
    let (xt, xstep) = linear_ticks(s0, s1, 8);
    let xt: Vec<(i32, f64)> = xt.into_iter().map(|v| (x_px(v), v)).collect();
    draw_x_ticks(root, lettering, &xt, xstep, TOP + ph, grey, black)?;
    let (yt, ystep) = linear_ticks(t0, t1, 6);
    let yt: Vec<(i32, f64)> = yt.into_iter().map(|v| (y_px(v), v)).collect();
    draw_y_ticks(root, lettering, &yt, ystep, LEFT, grey, black)?;
    draw_text(root, lettering, "t", (30, TOP + ph / 2 - 7), HPos::Left, 2, black)?;
    draw_text(
        root,
        lettering,
        &figure.x_label,
        (LEFT + pw / 2, TOP + ph + 32),
        HPos::Center,
        2,
        black,
    )?;
    draw_zone_legend(root, lettering, (LEFT, TOP + ph + 70), grey, black)
}
