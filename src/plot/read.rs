//! Reading a run back for its pictures: `gamma3.csv` through the csv crate (a bad row is an error
//! naming its line), Γ₃'s nodes placed on the mesh and ordered by arc length.

use crate::mesh::topology::edge_area_vector;
use crate::mesh::Mesh;
use crate::plot::kit::bounding_box;
use std::collections::HashMap;

/// Γ₃ of a 2D run as `gamma3.csv` gives it, located on the mesh.
pub struct Gamma3 {
    /// Mesh node of each Γ₃ node (in the CSV's order).
    pub nodes: Vec<usize>,
    /// Outward unit normal at each (from the boundary edges between Γ₃ nodes).
    pub normals: Vec<[f64; 2]>,
    /// Arc length of each from the start of Γ₃ (see [`arc_length`]).
    pub arc: Vec<f64>,
    /// The Γ₃ nodes (indices into `nodes`) in order along Γ₃.
    pub order: Vec<usize>,
    /// Per output time, (u_ν, pressure) of each node.
    pub times: Vec<(f64, Vec<(f64, f64)>)>,
    /// Per output time, the friction status of each node (0 separated, 1 stick, 2 slip, −1
    /// none; docs/method.md §17.5); empty for a run without friction.
    pub friction: Vec<Vec<i32>>,
}

/// A CSV reader of hvi's tables (`csv` crate: quoted cells, cells trimmed); rows of any length,
/// checked by [`read_numeric_csv`].
pub(super) fn csv_reader(text: &str) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes())
}

/// The header of the CSV table `text` (read from the file `name`, which messages name).
pub(super) fn read_csv_header(name: &str, text: &str) -> Result<Vec<String>, String> {
    let mut reader = csv_reader(text);
    let header = reader
        .headers()
        .map_err(|e| format!("{name}: cannot read the header: {e}"))?;
    Ok(header.iter().map(str::to_string).collect())
}

/// The header and the rows of the all-numeric CSV table `text` (read from the file `name`): a
/// row that is not valid CSV, has another length than the header or holds a cell that is not a
/// number is an error naming the file and the line.
pub(super) fn read_numeric_csv(name: &str, text: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let header = read_csv_header(name, text)?;
    let mut reader = csv_reader(text);
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| match e.position() {
            Some(p) => format!("{name} line {}: {e}", p.line()),
            None => format!("{name}: {e}"),
        })?;
        let line = record.position().map_or(0, |p| p.line());
        if record.len() != header.len() {
            return Err(format!(
                "{name} line {line}: {} fields, but the header `{}` has {} columns",
                record.len(),
                header.join(","),
                header.len()
            ));
        }
        let row = record
            .iter()
            .zip(&header)
            .map(|(cell, column)| {
                cell.parse::<f64>()
                    .map_err(|_| format!("{name} line {line}: `{cell}` in column `{column}` is not a number"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        rows.push(row);
    }
    Ok((header, rows))
}

/// Reads `gamma3.csv` (`time,x,y,u_nu,force,pressure,status`) and places its nodes on the mesh
/// (a row with a `group` on a node of that group: two bodies' nodes may share a position, §18);
/// a row that does not parse is an error naming its line.
pub fn read_gamma3(csv: &str, mesh: &Mesh<2>) -> Result<Gamma3, String> {
    let (header, rows) = read_numeric_csv("gamma3.csv", csv)?;
    let column = |name: &str| {
        header.iter().position(|c| *c == name).ok_or_else(|| {
            format!(
                "gamma3.csv has no `{name}` column (header `{}`; a 2D run writes `time,x,y,u_nu,force,pressure,status`)",
                header.join(",")
            )
        })
    };
    let cols = [
        column("time")?,
        column("x")?,
        column("y")?,
        column("u_nu")?,
        column("pressure")?,
    ];
    let status = header.iter().position(|c| c == "friction_status");
    let group = header.iter().position(|c| c == "group");
    let mut times: Vec<(f64, Vec<(f64, f64)>)> = Vec::new();
    let mut friction: Vec<Vec<i32>> = Vec::new();
    let mut positions: Vec<[f64; 2]> = Vec::new();
    let mut tags: Vec<Option<i32>> = Vec::new();
    for v in rows {
        let [t, x, y, un, p] = cols.map(|c| v[c]);
        if times.last().is_none_or(|(s, _)| *s != t) {
            times.push((t, Vec::new()));
            friction.push(Vec::new());
        }
        if times.len() == 1 {
            positions.push([x, y]);
            tags.push(group.map(|c| v[c]).filter(|g| g.is_finite()).map(|g| g as i32));
        }
        times.last_mut().expect("pushed above").1.push((un, p));
        if let Some(c) = status {
            let code = v[c];
            friction
                .last_mut()
                .expect("pushed above")
                .push(if code.is_finite() { code as i32 } else { -1 });
        }
    }
    let complete: Vec<bool> = times.iter().map(|(_, rows)| rows.len() == positions.len()).collect();
    let mut keep = complete.iter();
    times.retain(|_| *keep.next().expect("one flag per time"));
    let mut keep = complete.iter();
    friction.retain(|_| *keep.next().expect("one flag per time"));
    if status.is_none() {
        friction.clear();
    }
    if positions.is_empty() || times.is_empty() {
        return Err("gamma3.csv has no complete time block: nothing to draw along Γ₃".into());
    }
    // the mesh node at each CSV position (the CSV prints coordinates to full precision)
    let (lo, hi) = bounding_box(&mesh.points);
    let tol = 1e-9 * ((hi[0] - lo[0]).abs() + (hi[1] - lo[1]).abs()).max(1e-300);
    let key = |p: [f64; 2]| ((p[0] / tol).round() as i64, (p[1] / tol).round() as i64);
    let by_position: HashMap<(i64, i64), usize> = mesh.points.iter().enumerate().map(|(i, &p)| (key(p), i)).collect();
    // where two bodies touch, two nodes share a position: the row's own group's node first
    let mut by_group: HashMap<(i32, (i64, i64)), usize> = HashMap::new();
    for g in mesh.groups.iter().filter(|g| g.dim == 1) {
        for f in &g.facets {
            for &q in f.nodes() {
                by_group.insert((g.tag, key(mesh.points[q])), q);
            }
        }
    }
    let nodes: Vec<usize> = positions
        .iter()
        .zip(&tags)
        .map(|(&p, tag)| {
            tag.and_then(|t| by_group.get(&(t, key(p))))
                .or_else(|| by_position.get(&key(p)))
                .copied()
                .or_else(|| {
                    (0..mesh.points.len())
                        .find(|&i| (mesh.points[i][0] - p[0]).abs() <= tol && (mesh.points[i][1] - p[1]).abs() <= tol)
                })
                .ok_or_else(|| {
                    format!(
                        "gamma3.csv names the point ({}, {}), which is no node of the mesh",
                        p[0], p[1]
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    let (arc, order, normals) = arc_length(mesh, &nodes);
    Ok(Gamma3 {
        nodes,
        normals,
        arc,
        order,
        times,
        friction,
    })
}

/// Arc length along the curve through `nodes` (mesh nodes of a boundary part): the boundary
/// edges of the mesh joining two of them, chained from an end (the lowest, then leftmost,
/// end; any node of a closed curve), further pieces continuing the count. Returns each node's
/// arc length, the nodes' order along the curve and each node's outward unit normal (the
/// length-weighted mean of its edges' outward normals).
pub fn arc_length(mesh: &Mesh<2>, nodes: &[usize]) -> (Vec<f64>, Vec<usize>, Vec<[f64; 2]>) {
    let index: HashMap<usize, usize> = nodes.iter().enumerate().map(|(k, &p)| (p, k)).collect();
    // boundary edges (used by one cell), with the centroid of their cell for the outward side
    // (ordered: the normals' sums are added in the same order on every run)
    let mut edges: std::collections::BTreeMap<[usize; 2], (usize, [f64; 2])> = std::collections::BTreeMap::new();
    for c in &mesh.cells {
        let n = c.nodes();
        let centroid = n.iter().fold([0.0; 2], |a, &p| {
            [
                a[0] + mesh.points[p][0] / n.len() as f64,
                a[1] + mesh.points[p][1] / n.len() as f64,
            ]
        });
        for [a, b] in c.edges() {
            edges.entry([a.min(b), a.max(b)]).or_insert((0, centroid)).0 += 1;
        }
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    let mut normals = vec![[0.0; 2]; nodes.len()];
    for (&[a, b], &(count, centroid)) in &edges {
        if count != 1 {
            continue;
        }
        let (Some(&ka), Some(&kb)) = (index.get(&a), index.get(&b)) else {
            continue;
        };
        neighbours[ka].push(kb);
        neighbours[kb].push(ka);
        let (pa, pb) = (mesh.points[a], mesh.points[b]);
        let (d, _) = edge_area_vector(&pa, &pb);
        let mut n = [d[0], d[1]]; // (dy, −dx): |n| = edge length
        let mid = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
        if (mid[0] - centroid[0]) * n[0] + (mid[1] - centroid[1]) * n[1] < 0.0 {
            n = [-n[0], -n[1]];
        }
        for k in [ka, kb] {
            normals[k][0] += n[0];
            normals[k][1] += n[1];
        }
    }
    for n in normals.iter_mut() {
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        if len > 0.0 {
            *n = [n[0] / len, n[1] / len];
        }
    }
    let p = |k: usize| mesh.points[nodes[k]];
    let lowest = |ks: &mut dyn Iterator<Item = usize>| {
        ks.min_by(|&a, &b| p(a)[1].total_cmp(&p(b)[1]).then(p(a)[0].total_cmp(&p(b)[0])))
    };
    let mut arc = vec![0.0; nodes.len()];
    let mut order = Vec::with_capacity(nodes.len());
    let mut seen = vec![false; nodes.len()];
    let mut s = 0.0;
    while order.len() < nodes.len() {
        let unseen = || (0..nodes.len()).filter(|&k| !seen[k]);
        let start = lowest(&mut unseen().filter(|&k| neighbours[k].len() <= 1))
            .or_else(|| lowest(&mut unseen()))
            .expect("an unseen node remains");
        let mut at = start;
        loop {
            seen[at] = true;
            arc[at] = s;
            order.push(at);
            let Some(&next) = neighbours[at].iter().find(|&&k| !seen[k]) else {
                break;
            };
            s += ((p(next)[0] - p(at)[0]).powi(2) + (p(next)[1] - p(at)[1]).powi(2)).sqrt();
            at = next;
        }
    }
    (arc, order, normals)
}
