//! The Γ₃ figure of a 2D run: u_ν and the contact pressure against arc length at chosen times,
//! with the bound g.

use super::kit::{draw_text, draw_x_ticks, err, field_range, linear_ticks, tick_label, zone_colour, Lettering};
use crate::plot::colour_map;
use crate::plot::kit::sci_text;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::path::Path;

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
    /// The friction status at the nodes at the last time drawn (1 stick, 2 slip; other codes are
    /// not marked), for a run with friction (docs/method.md §17.5).
    pub zones: Option<Vec<i32>>,
}

pub(super) const FIG_W: i32 = 1100;

pub(super) const PANEL_H: i32 = 300;

pub(super) const LEFT: i32 = 120;

pub(super) const RIGHT: i32 = 170;

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

pub(super) fn time_colour(i: usize, n: usize) -> RGBColor {
    colour_map(if n > 1 { 0.9 * i as f64 / (n - 1) as f64 } else { 0.0 })
}

pub(super) fn draw_gamma3<DB: DrawingBackend>(
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
        // the stick and slip zones at the last time: a band of marks along the pressure panel's
        // foot (docs/method.md §17.5)
        if let (1, Some(zones)) = (k, &figure.zones) {
            for (&s, &code) in figure.arc.iter().zip(zones) {
                if let Some(colour) = zone_colour(code) {
                    let (x, _) = to_px(s, v0);
                    root.draw(&Rectangle::new(
                        [(x - 2, top + PANEL_H - 10), (x + 2, top + PANEL_H - 2)],
                        colour.filled(),
                    ))
                    .map_err(err)?;
                }
            }
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
        if let (1, Some(_)) = (k, &figure.zones) {
            for (code, label) in [(1, "stick"), (2, "slip")] {
                let colour = zone_colour(code).expect("a marked code");
                root.draw(&Rectangle::new([(lx + 8, ly + 3), (lx + 16, ly + 11)], colour.filled()))
                    .map_err(err)?;
                draw_text(root, lettering, label, (lx + 30, ly), HPos::Left, 2, black)?;
                ly += 20;
            }
        }
    }
    Ok(())
}
