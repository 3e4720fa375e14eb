//! Plots of a study (plotters, no system fonts): log–log error plots as SVG, the normal
//! displacement along Γ₃ as SVG, and the deformed mesh coloured by a cell value as PNG
//! (no text, so no font is needed for the bitmap).

use super::report::fraction;
use super::runner::{Refinement, Row};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

pub(crate) const FONT: &str = "sans-serif";
const SIZE: (u32, u32) = (820, 600);

pub(crate) fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Tick label of a log axis: `1e-3`, `2e-3`, `2.5e-3`, or plain for 0.01 ≤ |v| < 1000.
pub fn sci(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    let m = v / 10f64.powi(e);
    let m = if (m - m.round()).abs() < 1e-6 {
        format!("{}", m.round())
    } else {
        format!("{:.2}", m)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    };
    if (-2..3).contains(&e) {
        let decimals = (-e).max(0) as usize + 2;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        return s;
    }
    format!("{m}e{e}")
}

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
/// Returns false (and writes nothing) when no two runs share a k: nothing to draw.
pub fn plot_error_vs_h(path: &Path, rows: &[Row]) -> Result<bool, String> {
    plot_error_against(
        path,
        rows,
        |r| (r.summary.h, r.summary.k),
        ("h", "k"),
        ("O(h)", 1.0),
        "the mesh size",
    )
}

/// H¹-seminorm error at T against k, one line per h, with an O(k²) guide; false (nothing
/// written) when no two runs share an h.
pub fn plot_error_vs_k(path: &Path, rows: &[Row]) -> Result<bool, String> {
    plot_error_against(
        path,
        rows,
        |r| (r.summary.k, r.summary.h),
        ("k", "h"),
        ("O(k²)", 2.0),
        "the time step",
    )
}

/// The H¹ error at T against the parameter `param(row).0`, one line per value of `param(row).1`.
fn plot_error_against(
    path: &Path,
    rows: &[Row],
    param: impl Fn(&Row) -> (f64, f64),
    (x_name, line_name): (&str, &str),
    (guide_name, guide_order): (&str, f64),
    what: &str,
) -> Result<bool, String> {
    let groups = group_by(rows, |r| param(r).1, |r| param(r).0);
    if groups.is_empty() {
        return Ok(false);
    }
    let series: Vec<Series> = groups
        .iter()
        .map(|(fixed, v)| Series {
            name: format!("{line_name} = {}", fraction(*fixed)),
            points: v.iter().map(|r| (param(r).0, r.errors.at_final.h1_seminorm)).collect(),
            labels: vec![],
        })
        .collect();
    let guides = guide_at_finest(&series, guide_name, guide_order)
        .into_iter()
        .collect::<Vec<_>>();
    loglog_svg(
        path,
        &format!("H¹-seminorm error at T against {what}"),
        x_name,
        "|u_ref − u_hk|₁ at T",
        &series,
        &guides,
    )?;
    Ok(true)
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
                        Refinement::K => format!("k={}", fraction(r.summary.k)),
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

/// A perceptual blue–green–yellow colour map (viridis, 9 stops) at s ∈ [0, 1].
pub fn colour_map(s: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 45, 123),
        (59, 82, 139),
        (44, 114, 142),
        (33, 145, 140),
        (40, 174, 128),
        (94, 201, 98),
        (173, 220, 48),
        (253, 231, 37),
    ];
    let s = if s.is_finite() { s.clamp(0.0, 1.0) } else { 0.0 };
    let f = s * (STOPS.len() - 1) as f64;
    let i = (f.floor() as usize).min(STOPS.len() - 2);
    let w = f - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + w * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

// ---------------------------------------------------------------------------------------------
// Γ₃ of a 3D run: colour maps of nodal values over the contact surface, projected onto a plane

/// The two coordinates (indices into x, y, z, in increasing order) with the largest spread of
/// the points, and the points projected onto them: the plane of a flat Γ₃.
pub fn project_surface(points: &[[f64; 3]]) -> ([usize; 2], Vec<[f64; 2]>) {
    let spread = |d: usize| {
        let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[d]), b.max(p[d]))
        });
        if hi >= lo {
            hi - lo
        } else {
            0.0
        }
    };
    let mut dims = [0usize, 1, 2];
    // stable: of equal spreads the lower index wins
    dims.sort_by(|&a, &b| spread(b).total_cmp(&spread(a)));
    let mut axes = [dims[0], dims[1]];
    axes.sort_unstable();
    let projected = points.iter().map(|p| [p[axes[0]], p[axes[1]]]).collect();
    (axes, projected)
}

/// One panel of a surface map: a nodal field with its title and its name on the colour bar.
pub struct MapPanel {
    pub title: String,
    pub name: String,
    pub values: Vec<f64>,
}

/// Nodal fields over a surface projected onto a plane: node `i` at `points[i]`, drawn as its
/// tile (the part of the plane nearer to it than to any other node, within the node spacing:
/// on a structured grid, the square of the spacing around the node),
/// outlined when `marked[i]`.
pub struct SurfaceMap {
    /// Names of the horizontal and the vertical coordinate.
    pub axes: [String; 2],
    pub points: Vec<[f64; 2]>,
    pub marked: Vec<bool>,
    /// What an outline means, for the legend.
    pub marked_meaning: String,
    pub panels: Vec<MapPanel>,
}

/// Clips the convex polygon to the half-plane {q : (q − m)·n ≤ 0} (Sutherland–Hodgman).
fn clip_half_plane(poly: &[[f64; 2]], m: [f64; 2], n: [f64; 2]) -> Vec<[f64; 2]> {
    let side = |q: [f64; 2]| (q[0] - m[0]) * n[0] + (q[1] - m[1]) * n[1];
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (sa, sb) = (side(a), side(b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
            let w = sa / (sa - sb);
            out.push([a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1])]);
        }
    }
    out
}

/// The tile of every node (see [`SurfaceMap`]): its Voronoi cell clipped to the square of
/// half-width R around it and to the bounding box of the nodes widened by R/2 each way, R the
/// largest distance from a node to its nearest neighbour (on a grid of spacing h, R = h and
/// every tile is the h × h square around its node, also at the edges).
pub fn node_tiles(points: &[[f64; 2]]) -> Vec<Vec<[f64; 2]>> {
    let n = points.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[a][0].total_cmp(&points[b][0]));
    let xs: Vec<f64> = order.iter().map(|&i| points[i][0]).collect();
    let dist2 = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
    // nearest neighbours, scanning outward in x from each node
    let mut r: f64 = 0.0;
    for (k, &i) in order.iter().enumerate() {
        let p = points[i];
        let mut best = f64::INFINITY;
        for &j in order[k + 1..].iter() {
            if (points[j][0] - p[0]).powi(2) >= best {
                break;
            }
            let d = dist2(p, points[j]);
            if d > 0.0 {
                best = best.min(d);
            }
        }
        for &j in order[..k].iter().rev() {
            if (points[j][0] - p[0]).powi(2) >= best {
                break;
            }
            let d = dist2(p, points[j]);
            if d > 0.0 {
                best = best.min(d);
            }
        }
        if best.is_finite() {
            r = r.max(best.sqrt());
        }
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    if r == 0.0 {
        r = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
    }
    for d in 0..2 {
        lo[d] -= r / 2.0;
        hi[d] += r / 2.0;
    }
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let (x0, x1) = ((p[0] - r).max(lo[0]), (p[0] + r).min(hi[0]));
            let (y0, y1) = ((p[1] - r).max(lo[1]), (p[1] + r).min(hi[1]));
            let mut poly = vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
            let first = xs.partition_point(|&x| x < p[0] - 2.0 * r);
            for &j in &order[first..] {
                let q = points[j];
                if q[0] > p[0] + 2.0 * r {
                    break;
                }
                if j == i || (q[1] - p[1]).abs() >= 2.0 * r || q == p {
                    continue;
                }
                let m = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
                poly = clip_half_plane(&poly, m, [q[0] - p[0], q[1] - p[1]]);
                if poly.len() < 3 {
                    break;
                }
            }
            poly
        })
        .collect()
}

/// Ticks at 1, 2 or 5 × 10^k covering [lo, hi] with at most about `count` intervals.
pub(crate) fn linear_ticks(lo: f64, hi: f64, count: usize) -> (Vec<f64>, f64) {
    let span = hi - lo;
    if !(span > 0.0 && span.is_finite()) {
        return (vec![lo], 1.0);
    }
    let raw = span / count.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0 * mag);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    ((first..=last).map(|k| k as f64 * step).collect(), step)
}

/// A tick label for a multiple of `step`: as many decimals as the step needs, no trailing zeros.
pub(crate) fn tick_label(v: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    minus_sign(if s == "-0" { "0".into() } else { s })
}

/// `-` as the minus sign −.
pub(crate) fn minus_sign(s: String) -> String {
    s.replace('-', "−")
}

/// 5×7 pixel glyphs (rows top down, `#` set, rows 7 and 8 the descender) for text on the bitmap
/// backend, which has no font without the `ttf`/`ab_glyph` features (and no system font here).
const GLYPHS: &[(char, &str)] = &[
    (' ', ""),
    ('!', "..#.. ..#.. ..#.. ..#.. ..#.. ..... ..#.."),
    ('"', ".#.#. .#.#. .#.#."),
    ('#', ".#.#. .#.#. ##### .#.#. ##### .#.#. .#.#."),
    ('%', "##... ##..# ...#. ..#.. .#... #..## ...##"),
    ('\'', "..#.. ..#.. .#..."),
    ('(', "...#. ..#.. .#... .#... .#... ..#.. ...#."),
    (')', ".#... ..#.. ...#. ...#. ...#. ..#.. .#..."),
    ('*', "..... ..#.. #.#.# .###. #.#.# ..#.. ....."),
    ('+', "..... ..#.. ..#.. ##### ..#.. ..#.. ....."),
    (',', "..... ..... ..... ..... ..... .##.. .##.. ..#.. .#..."),
    ('-', "..... ..... ..... .###. ..... ..... ....."),
    ('−', "..... ..... ..... ##### ..... ..... ....."),
    ('.', "..... ..... ..... ..... ..... .##.. .##.."),
    ('/', "..... ....# ...#. ..#.. .#... #.... ....."),
    ('0', ".###. #...# #..## #.#.# ##..# #...# .###."),
    ('1', "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('2', ".###. #...# ....# ...#. ..#.. .#... #####"),
    ('3', "##### ...#. ..#.. ...#. ....# #...# .###."),
    ('4', "...#. ..##. .#.#. #..#. ##### ...#. ...#."),
    ('5', "##### #.... ####. ....# ....# #...# .###."),
    ('6', "..##. .#... #.... ####. #...# #...# .###."),
    ('7', "##### ....# ...#. ..#.. .#... .#... .#..."),
    ('8', ".###. #...# #...# .###. #...# #...# .###."),
    ('9', ".###. #...# #...# .#### ....# ...#. .##.."),
    (':', "..... .##.. .##.. ..... .##.. .##.. ....."),
    (';', "..... .##.. .##.. ..... .##.. .##.. ..#.. .#..."),
    ('<', "...#. ..#.. .#... #.... .#... ..#.. ...#."),
    ('=', "..... ..... ##### ..... ##### ..... ....."),
    ('>', ".#... ..#.. ...#. ....# ...#. ..#.. .#..."),
    ('?', ".###. #...# ....# ...#. ..#.. ..... ..#.."),
    ('A', ".###. #...# #...# ##### #...# #...# #...#"),
    ('B', "####. #...# #...# ####. #...# #...# ####."),
    ('C', ".###. #...# #.... #.... #.... #...# .###."),
    ('D', "###.. #..#. #...# #...# #...# #..#. ###.."),
    ('E', "##### #.... #.... ####. #.... #.... #####"),
    ('F', "##### #.... #.... ####. #.... #.... #...."),
    ('G', ".###. #...# #.... #.### #...# #...# .####"),
    ('H', "#...# #...# #...# ##### #...# #...# #...#"),
    ('I', ".###. ..#.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('J', "..### ...#. ...#. ...#. ...#. #..#. .##.."),
    ('K', "#...# #..#. #.#.. ##... #.#.. #..#. #...#"),
    ('L', "#.... #.... #.... #.... #.... #.... #####"),
    ('M', "#...# ##.## #.#.# #.#.# #...# #...# #...#"),
    ('N', "#...# #...# ##..# #.#.# #..## #...# #...#"),
    ('O', ".###. #...# #...# #...# #...# #...# .###."),
    ('P', "####. #...# #...# ####. #.... #.... #...."),
    ('Q', ".###. #...# #...# #...# #.#.# #..#. .##.#"),
    ('R', "####. #...# #...# ####. #.#.. #..#. #...#"),
    ('S', ".#### #.... #.... .###. ....# ....# ####."),
    ('T', "##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#.."),
    ('U', "#...# #...# #...# #...# #...# #...# .###."),
    ('V', "#...# #...# #...# #...# #...# .#.#. ..#.."),
    ('W', "#...# #...# #...# #.#.# #.#.# #.#.# .#.#."),
    ('X', "#...# #...# .#.#. ..#.. .#.#. #...# #...#"),
    ('Y', "#...# #...# #...# .#.#. ..#.. ..#.. ..#.."),
    ('Z', "##### ....# ...#. ..#.. .#... #.... #####"),
    ('[', ".###. .#... .#... .#... .#... .#... .###."),
    (']', ".###. ...#. ...#. ...#. ...#. ...#. .###."),
    ('_', "..... ..... ..... ..... ..... ..... ..... #####"),
    ('a', "..... ..... .###. ....# .#### #...# .####"),
    ('b', "#.... #.... #.##. ##..# #...# #...# ####."),
    ('c', "..... ..... .###. #.... #.... #...# .###."),
    ('d', "....# ....# .##.# #..## #...# #...# .####"),
    ('e', "..... ..... .###. #...# ##### #.... .###."),
    ('f', "..##. .#..# .#... ###.. .#... .#... .#..."),
    ('g', "..... ..... .#### #...# #...# #...# .#### ....# .###."),
    ('h', "#.... #.... #.##. ##..# #...# #...# #...#"),
    ('i', "..#.. ..... .##.. ..#.. ..#.. ..#.. .###."),
    ('j', "...#. ..... ..##. ...#. ...#. ...#. ...#. #..#. .##.."),
    ('k', "#.... #.... #..#. #.#.. ##... #.#.. #..#."),
    ('l', ".##.. ..#.. ..#.. ..#.. ..#.. ..#.. .###."),
    ('m', "..... ..... ##.#. #.#.# #.#.# #.#.# #.#.#"),
    ('n', "..... ..... #.##. ##..# #...# #...# #...#"),
    ('o', "..... ..... .###. #...# #...# #...# .###."),
    ('p', "..... ..... ####. #...# #...# #...# ####. #.... #...."),
    ('q', "..... ..... .#### #...# #...# #...# .#### ....# ....#"),
    ('r', "..... ..... #.##. ##..# #.... #.... #...."),
    ('s', "..... ..... .###. #.... .###. ....# ####."),
    ('t', ".#... .#... ###.. .#... .#... .#..# ..##."),
    ('u', "..... ..... #...# #...# #...# #..## .##.#"),
    ('v', "..... ..... #...# #...# #...# .#.#. ..#.."),
    ('w', "..... ..... #...# #...# #.#.# #.#.# .#.#."),
    ('x', "..... ..... #...# .#.#. ..#.. .#.#. #...#"),
    ('y', "..... ..... #...# #...# #...# #...# .#### ....# .###."),
    ('z', "..... ..... ##### ...#. ..#.. .#... #####"),
    ('ν', "..... ..... ##..# .#..# .#.#. .##.. .#..."),
    ('Γ', "##### #.... #.... #.... #.... #.... #...."),
    ('₃', "..... ..... ..... ..... .###. ...#. ..##. ...#. .###."),
    ('≤', "...#. ..#.. .#... ..#.. ...#. ..... .####"),
    ('·', "..... ..... ..... ..#.. ..... ..... ....."),
    ('×', "..... #...# .#.#. ..#.. .#.#. #...# ....."),
    ('|', "..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#.."),
    ('≈', "..... .#..# #.##. ..... .#..# #.##. ....."),
];

/// How text is drawn: with the pixel glyphs (bitmap) or as the backend's text (SVG).
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Lettering {
    Pixels,
    Native,
}

/// Width in pixels of `text` in the pixel glyphs at `scale` (6 columns a character).
pub(crate) fn text_width(text: &str, scale: i32) -> i32 {
    (text.chars().count() as i32 * 6 - 1).max(0) * scale
}

/// Tick marks hanging below a horizontal axis at pixel row `y`, and their labels: one per
/// (pixel column, value) of `ticks`, labelled by [`tick_label`] at the ticks' `step`.
pub(crate) fn draw_x_ticks<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lettering: Lettering,
    ticks: &[(i32, f64)],
    step: f64,
    y: i32,
    grey: RGBColor,
    black: RGBColor,
) -> Result<(), String> {
    for &(x, v) in ticks {
        root.draw(&PathElement::new(vec![(x, y), (x, y + 5)], grey.stroke_width(1)))
            .map_err(err)?;
        draw_text(
            root,
            lettering,
            &tick_label(v, step),
            (x, y + 9),
            HPos::Center,
            2,
            black,
        )?;
    }
    Ok(())
}

/// Draws `text` with its top (the top of a capital) at `y`, anchored at `x` by `h`; the
/// glyph cell is 5×7 `scale`-pixel squares (about 12·scale-point text in SVG).
pub(crate) fn draw_text<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lettering: Lettering,
    text: &str,
    (x, y): (i32, i32),
    h: HPos,
    scale: i32,
    colour: RGBColor,
) -> Result<(), String> {
    if lettering == Lettering::Native {
        let style = (FONT, 12.0 * scale as f64)
            .into_font()
            .color(&colour)
            .pos(Pos::new(h, VPos::Top));
        return root.draw_text(text, &style, (x, y)).map_err(err);
    }
    let w = text_width(text, scale);
    let mut cx = match h {
        HPos::Left => x,
        HPos::Center => x - w / 2,
        HPos::Right => x - w,
    };
    for ch in text.chars() {
        let rows = GLYPHS
            .iter()
            .find(|(c, _)| *c == ch)
            .map_or("##### #...# #...# #...# #...# #...# #####", |(_, g)| *g);
        for (r, row) in rows.split(' ').filter(|s| !s.is_empty()).enumerate() {
            for (c, bit) in row.chars().enumerate() {
                if bit == '#' {
                    let (px, py) = (cx + c as i32 * scale, y + r as i32 * scale);
                    root.draw(&Rectangle::new([(px, py), (px + scale, py + scale)], colour.filled()))
                        .map_err(err)?;
                }
            }
        }
        cx += 6 * scale;
    }
    Ok(())
}

/// Pixel geometry of a surface map (every panel alike).
struct MapLayout {
    /// Lower-left corner of the plotted region (data units) and pixels per unit.
    lo: [f64; 2],
    px: f64,
    /// Plot width and height, panel width and height, in pixels.
    plot: (i32, i32),
    panel: (i32, i32),
    columns: i32,
    rows: i32,
}

const MAP_LEFT: i32 = 110;
const MAP_RIGHT: i32 = 40;
const MAP_TOP: i32 = 44;
const BAR_WIDTH: i32 = 300;

/// The legend of the outlines.
fn marked_legend(map: &SurfaceMap) -> String {
    let count = map.marked.iter().filter(|m| **m).count();
    format!("{}, {count} of {}", map.marked_meaning, map.points.len())
}

fn map_layout(tiles: &[Vec<[f64; 2]>], panels: usize, legend: &str) -> MapLayout {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for q in tiles.iter().flatten() {
        for d in 0..2 {
            lo[d] = lo[d].min(q[d]);
            hi[d] = hi[d].max(q[d]);
        }
    }
    let span = [(hi[0] - lo[0]).max(1e-300), (hi[1] - lo[1]).max(1e-300)];
    // side by side unless the surface is a wide strip; panels stacked then
    let side_by_side = panels > 1 && span[0] <= 2.5 * span[1];
    let (max_w, max_h) = if side_by_side { (520.0, 460.0) } else { (850.0, 420.0) };
    let px = (max_w / span[0]).min(max_h / span[1]);
    let plot = (
        ((span[0] * px).round() as i32).max(1),
        ((span[1] * px).round() as i32).max(1),
    );
    let inner = plot.0.max(BAR_WIDTH + 160).max(22 + text_width(legend, 2));
    let panel = (MAP_LEFT + inner + MAP_RIGHT, MAP_TOP + plot.1 + 160);
    let columns = if side_by_side { panels as i32 } else { 1 };
    let rows = if side_by_side { 1 } else { panels.max(1) as i32 };
    MapLayout {
        lo,
        px,
        plot,
        panel,
        columns,
        rows,
    }
}

/// The colour range of a field: its min and max, values within 1e-9 of the largest magnitude
/// of 0 counted as 0 (round-off such as a pressure of −1e-17 where there is no contact).
pub(crate) fn field_range(values: &[f64]) -> (f64, f64) {
    let big = values
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let clean = |v: f64| if v.abs() <= 1e-9 * big { 0.0 } else { v };
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(clean(v)), b.max(clean(v)))
        })
}

fn draw_surface_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &SurfaceMap,
    tiles: &[Vec<[f64; 2]>],
    layout: &MapLayout,
    lettering: Lettering,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let black = RGBColor(0, 0, 0);
    let grey = RGBColor(90, 90, 90);
    let (pw, ph) = layout.plot;
    for (k, panel) in map.panels.iter().enumerate() {
        if panel.values.len() != map.points.len() {
            return Err(format!(
                "surface map: {} values of {} for {} nodes",
                panel.values.len(),
                panel.name,
                map.points.len()
            ));
        }
        let k = k as i32;
        let (ox, oy) = (
            (k % layout.columns) * layout.panel.0,
            (k / layout.columns) * layout.panel.1,
        );
        let (left, top) = (ox + MAP_LEFT, oy + MAP_TOP);
        let to_px = |q: [f64; 2]| {
            (
                left + ((q[0] - layout.lo[0]) * layout.px).round() as i32,
                top + ph - ((q[1] - layout.lo[1]) * layout.px).round() as i32,
            )
        };
        draw_text(root, lettering, &panel.title, (left, oy + 14), HPos::Left, 2, black)?;
        let (vmin, vmax) = field_range(&panel.values);
        let range = if vmax > vmin { vmax - vmin } else { 1.0 };
        // the tiles, each also stroked in its colour so that no seam shows between neighbours
        for (tile, v) in tiles.iter().zip(&panel.values) {
            if tile.len() < 3 {
                continue;
            }
            let colour = colour_map((v - vmin) / range);
            let poly: Vec<(i32, i32)> = tile.iter().map(|&q| to_px(q)).collect();
            root.draw(&Polygon::new(poly.clone(), colour.filled())).map_err(err)?;
            let mut closed = poly;
            closed.push(closed[0]);
            root.draw(&PathElement::new(closed, colour.stroke_width(1)))
                .map_err(err)?;
        }
        // outlines of the marked nodes: black with a white inner line, visible on any colour
        let inset = |tile: &[[f64; 2]], by: f64| -> Vec<(i32, i32)> {
            let n = tile.len() as f64;
            let c = tile.iter().fold([0.0, 0.0], |a, q| [a[0] + q[0] / n, a[1] + q[1] / n]);
            let mut v: Vec<(i32, i32)> = tile
                .iter()
                .map(|q| {
                    let (d0, d1) = (q[0] - c[0], q[1] - c[1]);
                    let len = (d0 * d0 + d1 * d1).sqrt().max(1e-300);
                    let s = (1.0 - by / (len * layout.px)).max(0.0);
                    to_px([c[0] + s * d0, c[1] + s * d1])
                })
                .collect();
            v.push(v[0]);
            v
        };
        for (tile, _) in tiles.iter().zip(&map.marked).filter(|(t, &m)| m && t.len() >= 3) {
            root.draw(&PathElement::new(inset(tile, 1.0), black.stroke_width(1)))
                .map_err(err)?;
            root.draw(&PathElement::new(inset(tile, 2.0), WHITE.stroke_width(1)))
                .map_err(err)?;
        }
        // frame, ticks and axis names
        root.draw(&Rectangle::new(
            [(left, top), (left + pw, top + ph)],
            grey.stroke_width(1),
        ))
        .map_err(err)?;
        let x_range = (layout.lo[0], layout.lo[0] + pw as f64 / layout.px);
        let y_range = (layout.lo[1], layout.lo[1] + ph as f64 / layout.px);
        let (xt, xstep) = linear_ticks(x_range.0, x_range.1, (pw / 90).clamp(2, 8) as usize);
        let xt: Vec<(i32, f64)> = xt.into_iter().map(|v| (to_px([v, layout.lo[1]]).0, v)).collect();
        draw_x_ticks(root, lettering, &xt, xstep, top + ph, grey, black)?;
        let (yt, ystep) = linear_ticks(y_range.0, y_range.1, (ph / 45).clamp(1, 6) as usize);
        for v in yt {
            let (_, y) = to_px([layout.lo[0], v]);
            root.draw(&PathElement::new(vec![(left - 5, y), (left, y)], grey.stroke_width(1)))
                .map_err(err)?;
            draw_text(
                root,
                lettering,
                &tick_label(v, ystep),
                (left - 9, y - 7),
                HPos::Right,
                2,
                black,
            )?;
        }
        draw_text(
            root,
            lettering,
            &map.axes[0],
            (left + pw / 2, top + ph + 30),
            HPos::Center,
            2,
            black,
        )?;
        draw_text(
            root,
            lettering,
            &map.axes[1],
            (ox + 14, top + ph / 2 - 7),
            HPos::Left,
            2,
            black,
        )?;
        // the colour bar: the field's name above, its min and max below
        let (bx, by) = (left, top + ph + 78);
        draw_text(root, lettering, &panel.name, (bx, by - 20), HPos::Left, 2, black)?;
        for i in 0..BAR_WIDTH {
            let colour = colour_map(i as f64 / (BAR_WIDTH - 1) as f64);
            root.draw(&Rectangle::new([(bx + i, by), (bx + i + 1, by + 16)], colour.filled()))
                .map_err(err)?;
        }
        root.draw(&Rectangle::new(
            [(bx, by), (bx + BAR_WIDTH, by + 16)],
            grey.stroke_width(1),
        ))
        .map_err(err)?;
        let (lo_label, hi_label) = if vmin.is_finite() {
            (minus_sign(sci(vmin)), minus_sign(sci(vmax)))
        } else {
            ("none".into(), "none".into())
        };
        for (x, label, h) in [
            (bx, format!("min {lo_label}"), HPos::Left),
            (bx + BAR_WIDTH, format!("max {hi_label}"), HPos::Right),
        ] {
            root.draw(&PathElement::new(
                vec![(x, by + 16), (x, by + 21)],
                grey.stroke_width(1),
            ))
            .map_err(err)?;
            draw_text(root, lettering, &label, (x, by + 25), h, 2, black)?;
        }
        // the legend of the outline
        let (lx, ly) = (bx, by + 52);
        root.draw(&Rectangle::new(
            [(lx, ly), (lx + 14, ly + 14)],
            RGBColor(200, 200, 200).filled(),
        ))
        .map_err(err)?;
        root.draw(&Rectangle::new([(lx, ly), (lx + 14, ly + 14)], black.stroke_width(2)))
            .map_err(err)?;
        root.draw(&Rectangle::new(
            [(lx + 3, ly + 3), (lx + 11, ly + 11)],
            WHITE.stroke_width(1),
        ))
        .map_err(err)?;
        draw_text(
            root,
            lettering,
            &marked_legend(map),
            (lx + 22, ly),
            HPos::Left,
            2,
            black,
        )?;
    }
    Ok(())
}

/// Draws the panels of a surface map side by side (or stacked, for a wide strip), each with a
/// colour bar (viridis between the field's min and max), to a PNG and, if given, an SVG file.
pub fn render_surface_map(png: &Path, svg: Option<&Path>, map: &SurfaceMap) -> Result<(), String> {
    if map.points.is_empty() {
        return Err("surface map: no node to draw".into());
    }
    if map.marked.len() != map.points.len() {
        return Err(format!(
            "surface map: {} marks for {} nodes",
            map.marked.len(),
            map.points.len()
        ));
    }
    let tiles = node_tiles(&map.points);
    let layout = map_layout(&tiles, map.panels.len(), &marked_legend(map));
    let size = (
        (layout.columns * layout.panel.0) as u32,
        (layout.rows * layout.panel.1) as u32,
    );
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_surface_map(&root, map, &tiles, &layout, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_surface_map(&root, map, &tiles, &layout, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}
