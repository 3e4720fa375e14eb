//! Plots of a study (plotters, no system fonts): log–log error plots as SVG, the normal
//! displacement along Γ₃ as SVG, and the deformed mesh coloured by a cell value as PNG
//! (no text, so no font is needed for the bitmap).

use super::format::fraction;
use super::level::LevelKind;
use super::runner::{Refinement, Row};
use crate::plot::kit::{err, sci, FONT};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (820, 600);

/// One polyline of a log–log plot, optionally with a text label at each point.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub labels: Vec<String>,
}

/// A dashed guide line e = c·x^slope through the anchor point, named in the legend.
pub struct Guide {
    pub name: String,
    pub slope: f64,
    pub anchor: (f64, f64),
}

/// Tick values m·10^e in [lo, hi]: every m = 1…9 if `light`, else the decades, with 2 and 5
/// added when the range spans less than two decades and every m when less than one.
pub fn log_ticks(lo: f64, hi: f64, light: bool) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return vec![];
    }
    let decades = (hi / lo).log10();
    let mantissas: &[f64] = if light || decades < 1.0 {
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    } else if decades < 2.0 {
        &[1.0, 2.0, 5.0]
    } else {
        &[1.0]
    };
    let mut ticks = Vec::new();
    for e in (lo.log10().floor() as i32)..=(hi.log10().ceil() as i32) {
        for m in mantissas {
            let v = m * 10f64.powi(e);
            if v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12) {
                ticks.push(v);
            }
        }
    }
    ticks
}

fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    (hi > 0.0).then(|| {
        let (lo, hi) = if hi / lo < 1.5 { (lo / 1.5, hi * 1.5) } else { (lo, hi) };
        let pad = (hi / lo).powf(0.06);
        (lo / pad, hi * pad)
    })
}

/// Draws a log–log plot of the series, with guide lines, to an SVG file.
pub fn loglog_svg(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    guides: &[Guide],
) -> Result<(), String> {
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    loglog(&root, title, x_desc, y_desc, series, guides)?;
    root.present().map_err(err)
}

fn loglog<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    guides: &[Guide],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let all = || series.iter().flat_map(|s| s.points.iter().copied());
    let Some((x0, mut x1)) = log_range(all().map(|p| p.0)) else {
        return Err(format!("{title}: nothing to plot"));
    };
    if series.iter().any(|s| !s.labels.is_empty()) {
        // room for the point labels on the right
        x1 *= (x1 / x0).powf(0.12);
    }
    let Some((y0, y1)) = log_range(all().map(|p| p.1)) else {
        return Err(format!("{title}: nothing to plot"));
    };
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 20))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (x0..x1)
                .log_scale()
                .with_key_points(log_ticks(x0, x1, false))
                .with_light_points(log_ticks(x0, x1, true)),
            (y0..y1)
                .log_scale()
                .with_key_points(log_ticks(y0, y1, false))
                .with_light_points(log_ticks(y0, y1, true)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&|v| sci(*v))
        .y_label_formatter(&|v| sci(*v))
        .bold_line_style(RGBColor(200, 200, 200))
        .light_line_style(RGBColor(240, 240, 240))
        .draw()
        .map_err(err)?;
    // the legend goes into the empty corner: upper left for rising data, lower left for falling
    let rising = series.iter().map(|s| {
        let (a, b) = (
            s.points.first().copied().unwrap_or((1.0, 1.0)),
            s.points.last().copied().unwrap_or((1.0, 1.0)),
        );
        (b.0 - a.0) * (b.1 - a.1)
    });
    let legend_position = if rising.sum::<f64>() >= 0.0 {
        SeriesLabelPosition::UpperLeft
    } else {
        SeriesLabelPosition::LowerLeft
    };
    for (i, g) in guides.iter().enumerate() {
        // the guide over the x range, clipped to the y range
        let f = |x: f64| g.anchor.1 * (x / g.anchor.0).powf(g.slope);
        let n = 64;
        let pts: Vec<(f64, f64)> = (0..=n)
            .map(|j| x0 * (x1 / x0).powf(j as f64 / n as f64))
            .map(|x| (x, f(x)))
            .filter(|&(_, y)| y >= y0 && y <= y1)
            .collect();
        let color = if i == 0 {
            RGBColor(120, 120, 120)
        } else {
            RGBColor(170, 120, 60)
        };
        chart
            .draw_series(std::iter::once(DashedPathElement::new(
                pts,
                6,
                4,
                color.stroke_width(1),
            )))
            .map_err(err)?
            .label(g.name.clone())
            .legend(move |(x, y)| DashedPathElement::new(vec![(x, y), (x + 20, y)], 4, 3, color.stroke_width(1)));
    }
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let mut pts = s.points.clone();
        pts.retain(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite());
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(s.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?;
        if !s.labels.is_empty() {
            chart
                .draw_series(s.points.iter().zip(&s.labels).map(|(&p, l)| {
                    EmptyElement::at(p) + Text::new(l.clone(), (6, -14), (FONT, 12).into_font().color(&color))
                }))
                .map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .position(legend_position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Unique runs of the rows (a run may sit on two paths).
fn unique_runs(rows: &[Row]) -> Vec<&Row> {
    let mut seen = Vec::new();
    rows.iter()
        .filter(|r| {
            let new = !seen.contains(&r.run);
            seen.push(r.run);
            new
        })
        .collect()
}

/// Groups runs by a parameter (to a relative 1e-9), each group sorted by the other.
fn group_by(rows: &[Row], key: impl Fn(&Row) -> f64, along: impl Fn(&Row) -> f64) -> Vec<(f64, Vec<&Row>)> {
    let mut groups: Vec<(f64, Vec<&Row>)> = Vec::new();
    for r in unique_runs(rows) {
        let k = key(r);
        match groups.iter_mut().find(|(g, _)| (g - k).abs() <= 1e-9 * k.abs()) {
            Some((_, v)) => v.push(r),
            None => groups.push((k, vec![r])),
        }
    }
    for (_, v) in groups.iter_mut() {
        v.sort_by(|a, b| along(b).total_cmp(&along(a)));
    }
    groups.sort_by(|a, b| b.0.total_cmp(&a.0));
    groups.retain(|(_, v)| v.len() >= 2);
    groups
}

/// H¹-seminorm error at T against h, one line per k (groups of ≥ 2 runs), with an O(h) guide.
/// Returns false (and writes nothing) when no two runs share a k: nothing to draw. Runs of a
/// level that is not uniform (steps per decade, a tolerance) are on no h line.
pub fn plot_error_vs_h(path: &Path, rows: &[Row]) -> Result<bool, String> {
    let uniform: Vec<Row> = rows.iter().filter(|r| r.summary.is_uniform()).cloned().collect();
    let series = lines_by(&uniform, |r| (r.summary.h, r.summary.k), "k");
    if series.is_empty() {
        return Ok(false);
    }
    let guides = guide_at_finest(&series, "O(h)", 1.0).into_iter().collect::<Vec<_>>();
    draw_error_against(path, &series, &guides, "h", "the mesh size")?;
    Ok(true)
}

/// H¹-seminorm error at T against k, one line per h, with an O(k²) guide; false (nothing
/// written) when no two runs share an h. A k path whose levels are not uniform is a line of its
/// own against its parameter (docs/method.md §6): the relative step 10^(1/s) − 1 of s steps per
/// decade (the guide's slope 2 holds for it too), or the tolerance; each point labelled with its
/// level.
pub fn plot_error_vs_k(path: &Path, rows: &[Row]) -> Result<bool, String> {
    let uniform: Vec<Row> = rows.iter().filter(|r| r.summary.is_uniform()).cloned().collect();
    let mut series = lines_by(&uniform, |r| (r.summary.k, r.summary.h), "h");
    let mut kinds: Vec<LevelKind> = Vec::new();
    if !series.is_empty() {
        kinds.push(LevelKind::Steps);
    }
    let mut names: Vec<&str> = Vec::new();
    for r in rows
        .iter()
        .filter(|r| r.refine == Refinement::K && !r.summary.is_uniform())
    {
        if !names.contains(&r.path.as_str()) {
            names.push(&r.path);
        }
    }
    let mut tolerance_only = Vec::new();
    for name in names {
        let on: Vec<&Row> = rows.iter().filter(|r| r.path == name).collect();
        let kind = on[0].summary.level.map_or(LevelKind::Steps, |l| l.kind());
        if !kinds.contains(&kind) {
            kinds.push(kind);
        }
        let line = Series {
            name: name.to_string(),
            points: on
                .iter()
                .map(|r| (r.summary.k, r.errors.at_final.h1_seminorm))
                .collect(),
            labels: on.iter().map(|r| r.summary.k_text()).collect(),
        };
        if kind == LevelKind::Tolerance {
            tolerance_only.push(line);
        } else {
            series.push(line);
        }
    }
    // the slope-2 guide through the lines of steps (uniform, per decade), not through tolerances
    let guide = if kinds.iter().all(|k| *k == LevelKind::Steps) {
        "O(k²)"
    } else {
        "slope 2"
    };
    let guides = guide_at_finest(&series, guide, 2.0).into_iter().collect::<Vec<_>>();
    series.extend(tolerance_only);
    if series.is_empty() {
        return Ok(false);
    }
    if kinds == [LevelKind::Steps] {
        draw_error_against(path, &series, &guides, "k", "the time step")?;
    } else {
        let x: Vec<&str> = kinds
            .iter()
            .map(|k| match k {
                LevelKind::Steps => "k = T/N",
                LevelKind::PerDecade => "10^(1/s) − 1 for s steps a decade",
                LevelKind::Tolerance => "the tolerance",
            })
            .collect();
        draw_error_against(path, &series, &guides, &x.join("; "), "the time levels")?;
    }
    Ok(true)
}

/// One line per value of `param(row).1` (groups of ≥ 2 runs), against `param(row).0`.
fn lines_by(rows: &[Row], param: impl Fn(&Row) -> (f64, f64), line_name: &str) -> Vec<Series> {
    group_by(rows, |r| param(r).1, |r| param(r).0)
        .iter()
        .map(|(fixed, v)| Series {
            name: format!("{line_name} = {}", fraction(*fixed)),
            points: v.iter().map(|r| (param(r).0, r.errors.at_final.h1_seminorm)).collect(),
            labels: vec![],
        })
        .collect()
}

/// The H¹ error at T of the series against `x_name`.
fn draw_error_against(
    path: &Path,
    series: &[Series],
    guides: &[Guide],
    x_name: &str,
    what: &str,
) -> Result<(), String> {
    loglog_svg(
        path,
        &format!("H¹-seminorm error at T against {what}"),
        x_name,
        "|u_ref − u_hk|₁ at T",
        series,
        guides,
    )
}

/// Work–precision: H¹ error at T against wall time, one line per refinement path, each point
/// labelled with its h and k, with a guide of slope −1/2 (error ∝ h ∝ work^(−1/2) in 2D);
/// false (nothing written) without a row.
pub fn plot_work_precision(path: &Path, rows: &[Row]) -> Result<bool, String> {
    if rows.is_empty() {
        return Ok(false);
    }
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.path.as_str()) {
            names.push(&r.path);
        }
    }
    let series: Vec<Series> = names
        .iter()
        .map(|name| {
            let on: Vec<&Row> = rows.iter().filter(|r| r.path == *name).collect();
            Series {
                name: name.to_string(),
                points: on
                    .iter()
                    .map(|r| (r.summary.wall.max(1e-6), r.errors.at_final.h1_seminorm))
                    .collect(),
                labels: on
                    .iter()
                    .map(|r| match r.refine {
                        Refinement::H => format!("h={}", fraction(r.summary.h)),
                        Refinement::K if r.summary.is_uniform() => format!("k={}", fraction(r.summary.k)),
                        Refinement::K => r.summary.k_text(),
                    })
                    .collect(),
            }
        })
        .collect();
    let anchor = series.first().and_then(|s| s.points.first().copied());
    let guides: Vec<Guide> = anchor
        .map(|a| Guide {
            name: "slope −1/2".into(),
            slope: -0.5,
            anchor: a,
        })
        .into_iter()
        .collect();
    loglog_svg(
        path,
        "Work–precision: H¹ error at T against wall time",
        "wall time [s]",
        "|u_ref − u_hk|₁ at T",
        &series,
        &guides,
    )?;
    Ok(true)
}

fn guide_at_finest(series: &[Series], name: &str, slope: f64) -> Option<Guide> {
    // through the finest point of the line whose finest point has the smallest error, shifted
    // down by a factor 2 so it does not hide the data
    let finest = series
        .iter()
        .filter_map(|s| s.points.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(Guide {
        name: name.into(),
        slope,
        anchor: (finest.0, finest.1 / 2.0),
    })
}

/// The normal displacement u_ν along Γ₃ at several times: `series` holds (t, [(s, u_ν)]), s the
/// arc length along Γ₃ (see [`crate::plot::arc_length`]).
pub fn plot_gamma3(path: &Path, title: &str, series: &[(f64, Vec<(f64, f64)>)]) -> Result<(), String> {
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let pts = || series.iter().flat_map(|(_, v)| v.iter().copied());
    let (x0, x1) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = pts().fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if !x0.is_finite() {
        return Err("Γ₃ plot: nothing to plot".into());
    }
    let x1 = if x1 > x0 { x1 } else { x0 + 1.0 };
    let pad = 0.06 * (y1 - y0).max(1e-12);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 18))
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("arc length s along Γ₃")
        .y_desc("u_ν")
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for (i, (t, v)) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let mut v = v.clone();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(v, color.stroke_width(2)))
            .map_err(err)?
            .label(format!("t = {t}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 13))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}
