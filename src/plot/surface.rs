//! Colour maps of a field over a surface in 3D (Γ₃ of a run, a study's error over Γ₃): the
//! surface projected on its best plane, each node's tile, and the panels with a colour bar.

use super::kit::{
    colour_map, draw_text, draw_x_ticks, draw_y_ticks, draw_zone_legend, err, field_range, linear_ticks, minus_sign,
    sci, text_width, zone_colour, Lettering, SEPARATED,
};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use std::path::Path;

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
    /// The values are friction status codes (docs/method.md §17.5): each piece takes its
    /// heaviest node's zone colour (stick, slip, else light grey), with a legend for a bar.
    pub zones: bool,
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
    /// The surface's own faces (indices into `points`, 3 or 4 each): drawn as they are, the
    /// colour interpolated in each, so that holes and fillets show as the mesh has them. Empty:
    /// node tiles ([`node_tiles`]), for a surface known only by its nodes.
    pub faces: Vec<Vec<usize>>,
}

/// A coloured polygon of a map and the nodal weights of its colour's value.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub polygon: Vec<[f64; 2]>,
    pub weights: Vec<(usize, f64)>,
}

/// Sub-divisions per face edge: the colour is interpolated over a face as s² flat pieces.
const FACE_SUBDIVISIONS: usize = 4;

/// The faces of a surface (triangles, bilinear quadrangles) cut into s × s pieces, each with
/// the weights (linear or bilinear shape values at its centre) of its colour: a map of the
/// surface as the mesh has it, clipped to it by construction.
pub fn face_pieces(points: &[[f64; 2]], faces: &[Vec<usize>], s: usize) -> Vec<Piece> {
    let mut out = Vec::new();
    let at = |f: &[usize], w: &[f64]| -> [f64; 2] {
        let mut x = [0.0; 2];
        for (&n, &wn) in f.iter().zip(w) {
            x[0] += wn * points[n][0];
            x[1] += wn * points[n][1];
        }
        x
    };
    let sf = s as f64;
    for f in faces {
        match f.len() {
            3 => {
                let bary = |u: f64, v: f64| [1.0 - u - v, u, v];
                let mut push = |corners: [(f64, f64); 3]| {
                    let c = corners
                        .iter()
                        .fold((0.0, 0.0), |a, q| (a.0 + q.0 / 3.0, a.1 + q.1 / 3.0));
                    out.push(Piece {
                        polygon: corners.iter().map(|&(u, v)| at(f, &bary(u, v))).collect(),
                        weights: f.iter().copied().zip(bary(c.0, c.1)).collect(),
                    });
                };
                for i in 0..s {
                    for j in 0..s - i {
                        let (u, v) = (i as f64 / sf, j as f64 / sf);
                        let d = 1.0 / sf;
                        push([(u, v), (u + d, v), (u, v + d)]);
                        if i + j + 1 < s {
                            push([(u + d, v), (u + d, v + d), (u, v + d)]);
                        }
                    }
                }
            }
            4 => {
                let bilinear = |x: f64, y: f64| [(1.0 - x) * (1.0 - y), x * (1.0 - y), x * y, (1.0 - x) * y];
                for i in 0..s {
                    for j in 0..s {
                        let (x0, y0, d) = (i as f64 / sf, j as f64 / sf, 1.0 / sf);
                        let corners = [(x0, y0), (x0 + d, y0), (x0 + d, y0 + d), (x0, y0 + d)];
                        out.push(Piece {
                            polygon: corners.iter().map(|&(x, y)| at(f, &bilinear(x, y))).collect(),
                            weights: f.iter().copied().zip(bilinear(x0 + d / 2.0, y0 + d / 2.0)).collect(),
                        });
                    }
                }
            }
            _ => {}
        }
    }
    out
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

fn draw_surface_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &SurfaceMap,
    pieces: &[Piece],
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
        // the pieces, each also stroked in its colour so that no seam shows between neighbours
        for piece in pieces {
            if piece.polygon.len() < 3 {
                continue;
            }
            let colour = if panel.zones {
                // the zone of the node that weighs most in the piece: sharp zone edges
                let heaviest =
                    piece.weights.iter().fold(
                        (usize::MAX, f64::NEG_INFINITY),
                        |a, &(n, w)| {
                            if w > a.1 {
                                (n, w)
                            } else {
                                a
                            }
                        },
                    );
                let code = panel.values.get(heaviest.0).map_or(-1, |&v| v as i32);
                zone_colour(code).unwrap_or(SEPARATED)
            } else {
                let v: f64 = piece.weights.iter().map(|&(n, w)| w * panel.values[n]).sum();
                colour_map((v - vmin) / range)
            };
            let poly: Vec<(i32, i32)> = piece.polygon.iter().map(|&q| to_px(q)).collect();
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
        if map.faces.is_empty() {
            // tile mode: piece i is node i's tile
            for (piece, _) in pieces
                .iter()
                .zip(&map.marked)
                .filter(|(t, &m)| m && t.polygon.len() >= 3)
            {
                root.draw(&PathElement::new(inset(&piece.polygon, 1.0), black.stroke_width(1)))
                    .map_err(err)?;
                root.draw(&PathElement::new(inset(&piece.polygon, 2.0), WHITE.stroke_width(1)))
                    .map_err(err)?;
            }
        } else {
            // face mode: a small square at each marked node
            for (p, _) in map.points.iter().zip(&map.marked).filter(|(_, &m)| m) {
                let (x, y) = to_px(*p);
                root.draw(&Rectangle::new([(x - 3, y - 3), (x + 3, y + 3)], black.stroke_width(1)))
                    .map_err(err)?;
                root.draw(&Rectangle::new([(x - 2, y - 2), (x + 2, y + 2)], WHITE.stroke_width(1)))
                    .map_err(err)?;
            }
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
        let yt: Vec<(i32, f64)> = yt.into_iter().map(|v| (to_px([layout.lo[0], v]).1, v)).collect();
        draw_y_ticks(root, lettering, &yt, ystep, left, grey, black)?;
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
        // the colour bar: the field's name above, its min and max below (zones: their legend)
        let (bx, by) = (left, top + ph + 78);
        draw_text(root, lettering, &panel.name, (bx, by - 20), HPos::Left, 2, black)?;
        if panel.zones {
            draw_zone_legend(root, lettering, (bx, by), grey, black)?;
            continue;
        }
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
    let pieces: Vec<Piece> = if map.faces.is_empty() {
        node_tiles(&map.points)
            .into_iter()
            .enumerate()
            .map(|(i, polygon)| Piece {
                polygon,
                weights: vec![(i, 1.0)],
            })
            .collect()
    } else {
        face_pieces(&map.points, &map.faces, FACE_SUBDIVISIONS)
    };
    let tiles: Vec<Vec<[f64; 2]>> = pieces.iter().map(|p| p.polygon.clone()).collect();
    let layout = map_layout(&tiles, map.panels.len(), &marked_legend(map));
    let size = (
        (layout.columns * layout.panel.0) as u32,
        (layout.rows * layout.panel.1) as u32,
    );
    let root = BitMapBackend::new(png, size).into_drawing_area();
    draw_surface_map(&root, map, &pieces, &layout, Lettering::Pixels)?;
    root.present().map_err(err)?;
    if let Some(svg) = svg {
        let root = SVGBackend::new(svg, size).into_drawing_area();
        draw_surface_map(&root, map, &pieces, &layout, Lettering::Native)?;
        root.present().map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contains(poly: &[[f64; 2]], x: [f64; 2]) -> bool {
        let mut inside = false;
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            if (a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (x[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
                inside = !inside;
            }
        }
        inside
    }

    /// A square plate 1 × 1 with a hole of radius 0.2 in its middle, meshed by quadrangles
    /// between the hole and the square (the surface of a part with a hole): the face pieces
    /// cover the plate and leave the hole empty to its edge (node tiles filled it, leaving a
    /// hole ~0.1 wide), and each piece's colour weights sum to 1.
    #[test]
    fn face_pieces_keep_a_hole_empty() {
        let (rings, around) = (4usize, 32usize);
        let mut points = Vec::new();
        for i in 0..=rings {
            let s = i as f64 / rings as f64;
            for j in 0..around {
                let a = std::f64::consts::TAU * j as f64 / around as f64;
                let (c, d) = (a.cos(), a.sin());
                // from the circle r = 0.2 to the square's edge along the ray
                let edge = 0.5 / c.abs().max(d.abs());
                let r = 0.2 + s * (edge - 0.2);
                points.push([0.5 + r * c, 0.5 + r * d]);
            }
        }
        let id = |i: usize, j: usize| i * around + j % around;
        let faces: Vec<Vec<usize>> = (0..rings)
            .flat_map(|i| (0..around).map(move |j| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]))
            .collect();
        let pieces = face_pieces(&points, &faces, FACE_SUBDIVISIONS);
        assert_eq!(pieces.len(), faces.len() * FACE_SUBDIVISIONS * FACE_SUBDIVISIONS);
        let covered = |x: [f64; 2]| pieces.iter().any(|p| contains(&p.polygon, x));
        for x in [
            [0.5, 0.5],
            [0.5 + 0.19, 0.5],
            [0.5, 0.5 - 0.19],
            [0.5 + 0.13, 0.5 + 0.13],
        ] {
            assert!(!covered(x), "the hole is drawn over at {x:?}");
        }
        for x in [[0.5 + 0.22, 0.5], [0.05, 0.05], [0.95, 0.5], [0.5, 0.9]] {
            assert!(covered(x), "the plate is not drawn at {x:?}");
        }
        for p in &pieces {
            let sum: f64 = p.weights.iter().map(|w| w.1).sum();
            assert!((sum - 1.0).abs() < 1e-12);
        }
        // tiles of the same nodes spill into the hole
        let tiles = node_tiles(&points);
        assert!(tiles.iter().any(|t| contains(t, [0.5 + 0.19, 0.5])));
    }
}
