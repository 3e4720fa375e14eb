//! A study's rows as a Markdown table and as CSV.

use super::format::fraction;
use super::runner::{Refinement, Row};
use std::fmt::Write;

/// The CSV columns, in order.
pub const CSV_COLUMNS: [&str; 18] = [
    "path",
    "h",
    "k",
    "nodes",
    "unknowns",
    "steps",
    "h1_error",
    "l2_error",
    "h1_max_over_time",
    "order",
    "wall_s",
    "assembly_s",
    "factorisation_s",
    "condensation_s",
    "steps_s",
    "output_s",
    "newton",
    "peak_rss_mb",
];

fn mb(bytes: Option<u64>) -> Option<f64> {
    bytes.map(|b| b as f64 / (1024.0 * 1024.0))
}

/// The rows as CSV (header [`CSV_COLUMNS`]; empty fields where there is no value). `k` is the
/// parameter of the time orders: T/N, the relative step of steps per decade, or the tolerance
/// (docs/method.md §6).
pub fn csv(rows: &[Row]) -> String {
    // through the csv crate: a path's name is quoted when it needs to be (RFC 4180)
    let mut writer = ::csv::WriterBuilder::new()
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    let fail = "a CSV row in memory is always written";
    writer.write_record(CSV_COLUMNS).expect(fail);
    for r in rows {
        let m = &r.summary;
        let p = &m.phases;
        let opt = |v: Option<f64>, prec: usize| v.map_or(String::new(), |v| format!("{v:.prec$}"));
        let record = [
            r.path.clone(),
            format!("{:e}", m.h),
            format!("{:e}", m.k),
            m.nodes.to_string(),
            m.unknowns.to_string(),
            m.steps.to_string(),
            format!("{:e}", r.errors.at_final.h1_seminorm),
            format!("{:e}", r.errors.at_final.l2),
            format!("{:e}", r.errors.h1_max_over_time),
            opt(r.order, 4),
            format!("{:.4}", m.wall),
            format!("{:.4}", p.assembly),
            format!("{:.4}", p.factorisation),
            format!("{:.4}", p.condensation),
            format!("{:.4}", m.steps_seconds()),
            format!("{:.4}", p.output),
            m.newton_total.to_string(),
            opt(mb(m.peak_rss_bytes), 1),
        ];
        writer.write_record(&record).expect(fail);
    }
    String::from_utf8(writer.into_inner().expect(fail)).expect("the fields are UTF-8")
}

/// An observed order for a table cell: two decimals, `–` where there is none.
fn ord(o: Option<f64>) -> String {
    o.map_or("–".to_string(), |o| format!("{o:.2}"))
}

/// The rows as one Markdown table (same columns as the CSV, h and k as fractions; a level that
/// is not uniform as the level, `10/decade` or `tol 1e-3`).
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| path | h | k | nodes | unknowns | steps | H¹ error at T | order | L² error at T | L² order | max_t H¹ error | order | wall [s] | assembly [s] | factorisation [s] | condensation [s] | steps [s] | output [s] | Newton | peak RSS [MB] |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    );
    for r in rows {
        let m = &r.summary;
        let p = &m.phases;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {:.6e} | {} | {:.6e} | {} | {:.6e} | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.2} | {:.3} | {} | {} |",
            r.path,
            fraction(m.h),
            m.k_text(),
            m.nodes,
            m.unknowns,
            m.steps,
            r.errors.at_final.h1_seminorm,
            ord(r.order),
            r.errors.at_final.l2,
            ord(r.l2_order),
            r.errors.h1_max_over_time,
            ord(r.max_order),
            m.wall,
            p.assembly,
            p.factorisation,
            p.condensation,
            m.steps_seconds(),
            p.output,
            m.newton_total,
            mb(m.peak_rss_bytes).map_or("–".into(), |v| format!("{v:.0}")),
        );
    }
    // non-nested meshes of a curved domain (docs/method.md §6.2)
    let extended: Vec<String> = rows
        .iter()
        .filter_map(|r| {
            let e = r.errors.extension?;
            Some(format!(
                "h = {}, k = {}: {} reference nodes outside its mesh, the farthest by {:.3e} (allowed {:.3e})",
                fraction(r.summary.h),
                r.summary.k_text(),
                e.points,
                e.farthest,
                e.allowed
            ))
        })
        .collect();
    if !extended.is_empty() {
        let _ = writeln!(
            s,
            "\nThe meshes are not nested and the boundary is curved: reference nodes outside a run's mesh (by the \
             O(h²) gap between two faceted approximations of one curved boundary, allowed up to twice the run's \
             boundary sagitta) were evaluated by extending the nearest cell's map (docs/method.md §6.2):\n"
        );
        for e in extended {
            let _ = writeln!(s, "* {e}");
        }
    }
    s
}

/// A compact table of one path: its parameter, the H¹ and L² errors at T with the observed
/// order between neighbouring runs, and the max-over-time H¹ error. A path whose levels are not
/// uniform shows each level (`10/decade`, `tol 1e-3`) and its number of steps.
pub fn path_markdown(rows: &[&Row]) -> String {
    let mut s = String::new();
    let uniform = rows.iter().all(|r| r.summary.is_uniform());
    if uniform {
        let _ = writeln!(
            s,
            "| h | k | H¹ error at T | order | L² error at T | L² order | max_t H¹ error | order |"
        );
        let _ = writeln!(s, "|---|---|--:|--:|--:|--:|--:|--:|");
    } else {
        let _ = writeln!(
            s,
            "| h | level | steps | H¹ error at T | order | L² error at T | L² order | max_t H¹ error | order |"
        );
        let _ = writeln!(s, "|---|---|--:|--:|--:|--:|--:|--:|--:|");
    }
    for r in rows {
        let level = if uniform {
            r.summary.k_text()
        } else {
            format!("{} | {}", r.summary.k_text(), r.summary.steps)
        };
        let _ = writeln!(
            s,
            "| {} | {level} | {:.6e} | {} | {:.6e} | {} | {:.6e} | {} |",
            fraction(r.summary.h),
            r.errors.at_final.h1_seminorm,
            ord(r.order),
            r.errors.at_final.l2,
            ord(r.l2_order),
            r.errors.h1_max_over_time,
            ord(r.max_order),
        );
    }
    s
}

/// A value printed beside ours: the paper's error and order for one run of a path.
#[derive(Clone, Copy, Debug)]
pub struct Published {
    pub error: f64,
    pub order: Option<f64>,
}

/// A compact table of one path beside published numbers (matched by position; missing
/// published entries are left blank).
pub fn comparison_markdown(rows: &[&Row], published: &[Published]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| h | k | H¹ error at T | order | paper's error | paper's order | ratio ours/paper | max_t H¹ error | order |"
    );
    let _ = writeln!(s, "|---|---|--:|--:|--:|--:|--:|--:|--:|");
    for (i, r) in rows.iter().enumerate() {
        let e = r.errors.at_final.h1_seminorm;
        let (pe, po, ratio) = match published.get(i) {
            Some(p) => (format!("{:.6e}", p.error), ord(p.order), format!("{:.2}", e / p.error)),
            None => (String::new(), String::new(), String::new()),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {e:.6e} | {} | {pe} | {po} | {ratio} | {:.6e} | {} |",
            fraction(r.summary.h),
            r.summary.k_text(),
            ord(r.order),
            r.errors.h1_max_over_time,
            ord(r.max_order)
        );
    }
    s
}

/// The rows of the paths refining `refine`.
pub fn rows_of(rows: &[Row], refine: Refinement) -> Vec<&Row> {
    rows.iter().filter(|r| r.refine == refine).collect()
}
