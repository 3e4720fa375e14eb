//! The history figure of a run (docs/outputs.md "Pictures without ParaView"): the largest u_ν on
//! Γ₃ at every output time — an indentation's depth, a creep curve — on a logarithmic time axis
//! when the output times span two decades or more (a run on steps growing with time, docs/method.md
//! §20), where t = 0 is left out.

use super::kit::{draw_text, draw_x_ticks, draw_y_ticks, err, field_range, linear_ticks, Lettering};
use crate::plot::kit::sci_text;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::path::Path;

/// Output times spanning at least this ratio (largest over smallest positive) get a log axis.
pub const LOG_AXIS_FROM: f64 = 100.0;

/// The history figure: one value per output time.
pub struct HistoryFigure {
    pub title: String,
    pub y_label: String,
    /// (t, value), increasing t.
    pub points: Vec<(f64, f64)>,
}

impl HistoryFigure {
    /// Whether its time axis is logarithmic: positive times spanning [`LOG_AXIS_FROM`] or more.
    pub fn log_time(&self) -> bool {
        let positive: Vec<f64> = self.points.iter().map(|p| p.0).filter(|&t| t > 0.0).collect();
        match (positive.first(), positive.last()) {
            (Some(&a), Some(&b)) => b / a >= LOG_AXIS_FROM,
            _ => false,
        }
    }
}

const FIG_W: i32 = 1100;
const PANEL_H: i32 = 420;
const LEFT: i32 = 130;
const RIGHT: i32 = 60;

/// Draws the figure to a PNG and, if given, an SVG file.
pub fn render_history(png: &Path, svg: Option<&Path>, figure: &HistoryFigure) -> Result<(), String> {
    if figure.points.len() < 2 {
        return Err("history plot: fewer than two output times".into());
    }
    let size = (FIG_W as u32, (60 + PANEL_H + 90) as u32);
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_history(&root, figure, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_history(&root, figure, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}

fn draw_history<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    figure: &HistoryFigure,
    lettering: Lettering,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let (black, grey) = (RGBColor(0, 0, 0), RGBColor(90, 90, 90));
    draw_text(root, lettering, &figure.title, (20, 14), HPos::Left, 2, black)?;
    let log = figure.log_time();
    // the axis variable: log10 t on a log axis (t = 0 left out), t otherwise
    let points: Vec<(f64, f64)> = figure
        .points
        .iter()
        .filter(|p| !log || p.0 > 0.0)
        .map(|&(t, v)| (if log { t.log10() } else { t }, v))
        .collect();
    let (x0, x1) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (x0, x1) = if log { (x0.floor(), x1.ceil()) } else { (x0, x1) };
    let x1 = if x1 > x0 { x1 } else { x0 + 1.0 };
    let values: Vec<f64> = points.iter().map(|p| p.1).collect();
    let (mut v0, mut v1) = field_range(&values);
    v0 = v0.min(0.0);
    if v1 <= v0 {
        v1 = v0 + 1.0;
    }
    let pad = 0.05 * (v1 - v0);
    let (v0, v1) = (v0, v1 + pad);
    let (top, pw) = (60, FIG_W - LEFT - RIGHT);
    let to_px = |x: f64, v: f64| {
        (
            LEFT + ((x - x0) / (x1 - x0) * pw as f64).round() as i32,
            top + PANEL_H - ((v - v0) / (v1 - v0) * PANEL_H as f64).round() as i32,
        )
    };
    root.draw(&Rectangle::new(
        [(LEFT, top), (LEFT + pw, top + PANEL_H)],
        grey.stroke_width(1),
    ))
    .map_err(err)?;
    draw_text(root, lettering, &figure.y_label, (LEFT, top - 22), HPos::Left, 2, black)?;
    if log {
        // a tick at every decade, labelled 10^k as "1ek"
        let decades: Vec<i32> = (x0 as i32..=x1 as i32).collect();
        let every = (decades.len() / 12 + 1) as i32;
        for &d in &decades {
            let (x, _) = to_px(d as f64, v0);
            root.draw(&PathElement::new(
                vec![(x, top), (x, top + PANEL_H)],
                RGBColor(235, 235, 235).stroke_width(1),
            ))
            .map_err(err)?;
            root.draw(&PathElement::new(
                vec![(x, top + PANEL_H), (x, top + PANEL_H + 5)],
                grey.stroke_width(1),
            ))
            .map_err(err)?;
            if d % every == 0 {
                let label = super::kit::minus_sign(format!("1e{d}"));
                draw_text(root, lettering, &label, (x, top + PANEL_H + 9), HPos::Center, 2, black)?;
            }
        }
    } else {
        let (xt, xstep) = linear_ticks(x0, x1, 8);
        let xt: Vec<(i32, f64)> = xt.into_iter().map(|v| (to_px(v, v0).0, v)).collect();
        draw_x_ticks(root, lettering, &xt, xstep, top + PANEL_H, grey, black)?;
    }
    let (yt, ystep) = linear_ticks(v0, v1, 6);
    let yt: Vec<(i32, f64)> = yt.into_iter().map(|v| (to_px(x0, v).1, v)).collect();
    for &(y, _) in &yt {
        root.draw(&PathElement::new(
            vec![(LEFT, y), (LEFT + pw, y)],
            RGBColor(235, 235, 235).stroke_width(1),
        ))
        .map_err(err)?;
    }
    draw_y_ticks(root, lettering, &yt, ystep, LEFT, grey, black)?;
    let x_label = if log {
        "time t (logarithmic)".to_string()
    } else {
        "time t".to_string()
    };
    draw_text(
        root,
        lettering,
        &x_label,
        (LEFT + pw / 2, top + PANEL_H + 36),
        HPos::Center,
        2,
        black,
    )?;
    let line: Vec<(i32, i32)> = points.iter().map(|&(x, v)| to_px(x, v)).collect();
    let blue = RGBColor(30, 80, 170);
    root.draw(&PathElement::new(line.clone(), blue.stroke_width(2)))
        .map_err(err)?;
    for p in line {
        root.draw(&Circle::new(p, 3, blue.filled())).map_err(err)?;
    }
    let last = figure.points.last().expect("two points");
    draw_text(
        root,
        lettering,
        &format!("at t = {}: {}", sci_text(last.0), sci_text(last.1)),
        (LEFT + pw, top - 22),
        HPos::Right,
        2,
        grey,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_of_output_times_get_a_log_axis() {
        let figure = |times: &[f64]| HistoryFigure {
            title: String::new(),
            y_label: String::new(),
            points: times.iter().map(|&t| (t, 1.0)).collect(),
        };
        assert!(figure(&[0.0, 1e-6, 1e-3, 1.0]).log_time());
        assert!(!figure(&[0.0, 0.25, 0.5, 1.0]).log_time());
        assert!(!figure(&[0.0, 1.0, 99.0]).log_time());
    }
}
