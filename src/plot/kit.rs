//! The drawing kit of hvi's pictures (the run's and the study's): the colour map, ticks and
//! their labels, and text in pixel glyphs, so that no system font is needed.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub(crate) const FONT: &str = "sans-serif";

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
pub(super) const GLYPHS: &[(char, &str)] = &[
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

/// A number as short text with the minus sign −.
pub(super) fn sci_text(v: f64) -> String {
    minus_sign(sci(v))
}

pub(super) fn bounding_box(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

/// The colour of a friction status code (docs/method.md §17.5) in the zone band of gamma3.png and
/// the zone panel of gamma3_map.png: stick green, slip orange; None for separated and no friction.
pub fn zone_colour(code: i32) -> Option<RGBColor> {
    match code {
        1 => Some(RGBColor(40, 150, 70)),
        2 => Some(RGBColor(230, 120, 20)),
        _ => None,
    }
}

/// Tick marks left of a vertical axis at pixel column `x`, and their labels: one per
/// (pixel row, value) of `ticks`, labelled by [`tick_label`] at the ticks' `step`.
pub(crate) fn draw_y_ticks<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lettering: Lettering,
    ticks: &[(i32, f64)],
    step: f64,
    x: i32,
    grey: RGBColor,
    black: RGBColor,
) -> Result<(), String> {
    for &(y, v) in ticks {
        root.draw(&PathElement::new(vec![(x - 5, y), (x, y)], grey.stroke_width(1)))
            .map_err(err)?;
        draw_text(
            root,
            lettering,
            &tick_label(v, step),
            (x - 9, y - 7),
            HPos::Right,
            2,
            black,
        )?;
    }
    Ok(())
}

/// The legend of the friction zones (stick, slip, separated swatches) from (x, y).
pub(crate) fn draw_zone_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    lettering: Lettering,
    (mut x, y): (i32, i32),
    grey: RGBColor,
    black: RGBColor,
) -> Result<(), String> {
    for (code, label) in [(1, "stick"), (2, "slip"), (0, "separated")] {
        let colour = zone_colour(code).unwrap_or(SEPARATED);
        root.draw(&Rectangle::new([(x, y), (x + 16, y + 16)], colour.filled()))
            .map_err(err)?;
        root.draw(&Rectangle::new([(x, y), (x + 16, y + 16)], grey.stroke_width(1)))
            .map_err(err)?;
        draw_text(root, lettering, label, (x + 22, y + 1), HPos::Left, 2, black)?;
        x += 30 + text_width(label, 2);
    }
    Ok(())
}

/// The colour of a separated node in the zone maps.
pub const SEPARATED: RGBColor = RGBColor(215, 215, 215);
