//! Creep under a constant indentation force of a relaxing, nearly incompressible gel: the
//! viscoelastic correspondence of Lee & Radok (docs/method.md §8.6, "Creep under a sphere").
//!
//! The gallery's gel (examples/gallery/gel): a body of revolution pressed by a rigid sphere
//! (R = 1) with a constant force P, its base force-controlled. The shear modulus relaxes 100-fold,
//! G(t) = 0.01 + 0.99 e^{−t}, the bulk modulus K = 10 stays (K/G from 10 to 1000, ν from 0.45 to
//! 0.4995). While the contact grows, Lee & Radok's solution is Hertz's with the elastic constant
//! replaced by its hereditary operator: a(t)³ = (3PR/4) C(t), C the creep function of the
//! operator (1 − ν²)/E = (3K + 4G)/(4G(3K + G)), found in closed form by residues.

mod common;

use common::{Compliance, ASPHALT, ASPHALT_E_INF, ASPHALT_NU};
use hvi::contact::NodeStatus;
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::Scene;
use hvi::solver::{timeloop, FrameSink, Simulation, SolveError, StepView};
use std::path::{Path, PathBuf};

const BULK: f64 = 10.0;
const SHEAR_AT_ONCE: f64 = 1.0;
const SHEAR_LONG_TERM: f64 = 0.01;
const TAU: f64 = 1.0;
const FORCE: f64 = 1.5e-5;
const RADIUS: f64 = 1.0;

fn gallery(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/gallery/gel")
        .join(file)
}

/// The creep function C(t) of (3K + 4G)/(4G(3K + G)) for the standard linear solid in shear,
/// G(t) = G∞ + (G₀ − G∞) e^{−t/τ}, and a constant K. In Carson's transform G is N/D with
/// N = G₀ s + G∞/τ, D = s + 1/τ, so C(s) = (3K D + 4N) D / (s · 4N (3K D + N)): poles at 0,
/// −G∞/(τ G₀) (the slow creep, here τ·100) and −(3K + G∞)/(τ (3K + G₀)); C(t) is the sum of the
/// residues of C(s) e^{st}.
fn creep_function(t: f64) -> f64 {
    let (k, g0, gi) = (BULK, SHEAR_AT_ONCE, SHEAR_LONG_TERM);
    let poles = [0.0, -gi / (TAU * g0), -(3.0 * k + gi) / (TAU * (3.0 * k + g0))];
    let numerator = |s: f64| {
        let d = s + 1.0 / TAU;
        let n = g0 * s + gi / TAU;
        (3.0 * k * d + 4.0 * n) * d
    };
    poles
        .iter()
        .enumerate()
        .map(|(i, &si)| {
            let others: f64 = poles
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &sj)| si - sj)
                .product();
            numerator(si) * (si * t).exp() / (4.0 * g0 * (3.0 * k + g0) * others)
        })
        .sum()
}

/// Lee & Radok's contact radius under the constant force.
fn lee_radok_radius(t: f64) -> f64 {
    (0.75 * FORCE * RADIUS * creep_function(t)).cbrt()
}

/// The contact radius of one step, from the gap g(r) = R − sqrt(R² − r²) − u_ν just outside
/// the contact: near the edge of a Hertzian contact the gap opens as c (r − a)^{3/2}, so the
/// first two free nodes r₁ < r₂ give (g₁/g₂)^{2/3} = (r₁ − a)/(r₂ − a), solved for a. (The
/// midpoint between the last node in contact and the first free one is within h/2 = 1 % of a on
/// this mesh, too coarse a ruler for a 2 % check.)
fn contact_radius<const D: usize>(sim: &Simulation<D>, view: &StepView) -> f64 {
    let contact = sim.contact.as_ref().expect("the gel scene has contact");
    let state = view.contact.expect("a contact state every step");
    let mut nodes: Vec<(f64, bool, f64)> = contact
        .nodes
        .nodes
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let r = sim.mesh.points[p][0];
            let gap = RADIUS - (RADIUS * RADIUS - r * r).sqrt() - state.normal_displacement[k];
            (r, state.status[k] == NodeStatus::OnBound, gap)
        })
        .collect();
    nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let last = nodes.iter().rposition(|n| n.1).expect("the sphere touches");
    let ((r1, _, g1), (r2, _, g2)) = (nodes[last + 1], nodes[last + 2]);
    let q = (g1 / g2).powf(2.0 / 3.0);
    (r1 - q * r2) / (1.0 - q)
}

/// Collects (t, a(t)) after every step, nothing else (the steps' fields are not kept).
struct Radii(Vec<(f64, f64)>);

impl<const D: usize> FrameSink<D> for Radii {
    fn step_done(&mut self, sim: &Simulation<D>, view: &StepView) {
        self.0.push((view.time, contact_radius(sim, view)));
    }
    fn write_frame(&mut self, _: &Simulation<D>, _: &StepView) -> Result<(), SolveError> {
        Ok(())
    }
}

/// The gallery scene on its mesh, to T = 24 (the slow creep a quarter done, a grown 2.7×) on its
/// steps growing 20 a decade from τ/1000 (84 steps), the memory integrated exactly for a
/// displacement linear over each step (docs/method.md §20.2). The mesh resolves the edge with
/// cells of a/50 (examples/gallery/gel/gel.geo). Measured: within 0.6 % of Lee & Radok at every
/// step (on the paper's trapezoid this took 800 uniform steps of τ/33 for 0.7 %); 2 % is the
/// issue's bound and leaves room for the mesh's 0.3 % (the long-term elastic Hertz run on the same
/// mesh) and the growing steps' part.
#[test]
fn a_gel_under_a_constant_force_creeps_as_lee_and_radok_predict() {
    let scene =
        Scene::load(Some(&gallery("gel.toml")), &["time.final_time=24".to_string()]).unwrap_or_else(|e| panic!("{e}"));
    let mesh: Mesh<2> = read_mesh(&gallery("gel.msh")).unwrap_or_else(|e| panic!("{e}"));
    let sim = Simulation::new(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let mut radii = Radii(Vec::new());
    timeloop::run(&sim, &mut radii, None).unwrap_or_else(|e| panic!("{e}"));
    assert!(radii.0.len() < 100, "{} steps: growing steps", radii.0.len());
    let mut worst = (0.0f64, 0.0);
    for &(t, a) in &radii.0 {
        let error = a / lee_radok_radius(t) - 1.0;
        if error.abs() > worst.0.abs() {
            worst = (error, t);
        }
    }
    let (t0, a0) = radii.0[0];
    let (t1, a1) = *radii.0.last().unwrap();
    eprintln!(
        "gel creep: a({t0}) = {a0:.5} (Lee-Radok {:.5}), a({t1}) = {a1:.5} (Lee-Radok {:.5}); \
         worst {:+.2} % at t = {}",
        lee_radok_radius(t0),
        lee_radok_radius(t1),
        100.0 * worst.0,
        worst.1
    );
    assert!(a1 > 2.5 * a0, "the contact creeps: a grew {:.2}×", a1 / a0);
    assert!(
        worst.0.abs() < 0.02,
        "a off Lee & Radok by {:+.3} % at t = {}",
        100.0 * worst.0,
        worst.1
    );
}

// ---------------------------------------------------------------------------------------------
// A real material: the gallery's asphalt concrete (examples/gallery/asphalt), 12 Prony terms over
// 14 decades, from a microsecond to a year on steps growing 20 a decade.

/// u_ν at the contact nodes of each frame: (t, u_ν).
fn contact_frames(scene: &Scene) -> (Vec<(f64, Vec<f64>)>, hvi::solver::RunStats) {
    let mesh: Mesh<2> = read_mesh(&gallery("gel.msh")).unwrap_or_else(|e| panic!("{e}"));
    let (_, stats, sink) = hvi::app::solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let frames = sink
        .steps
        .iter()
        .map(|s| (s.time, s.contact.as_ref().expect("contact").normal_displacement.clone()))
        .collect();
    (frames, stats)
}

/// Lee & Radok for a material whose Poisson's ratio stays: while the contact grows, the state at t
/// is the elastic one (modulus E(0)) under the force P E(0) D(t), D the creep compliance. The
/// gallery's asphalt scene (a microsecond to a year, steps growing 20 a decade, 252 steps, one
/// factorisation) against an elastic run of the same mesh under that force at each of its 15
/// frames (one a decade): u_ν at every contact node within 2·10⁻³ of the largest u_ν. The contact
/// radius creeps 70^{1/3} = 4.1-fold over the year.
#[test]
fn asphalt_under_a_sphere_creeps_as_lee_and_radok_predict() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene =
        Scene::load(Some(&root.join("examples/gallery/asphalt/asphalt.toml")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let force: f64 = scene.force_control[0].force.parse().expect("a constant force");
    let (creep, stats) = contact_frames(&scene);
    assert_eq!(stats.factorisations, 1, "every step matrix a multiple of K_A");
    assert_eq!(creep.len(), 16, "t = 0 and one frame a decade from 1e-6 s, and a year");
    let e0 = ASPHALT_E_INF + ASPHALT.iter().map(|(e, _)| e).sum::<f64>();
    let compliance = Compliance::asphalt();
    let mut worst = (0.0f64, 0.0);
    for (t, u) in &creep {
        let equivalent = force * e0 * compliance.at(*t);
        let elastic = Scene::from_toml_str(
            &format!(
                "[groups]\ncontact = \"Gamma3\"\n[material]\nplane = \"axisymmetric\"\nyoungs_modulus = {e0:e}\n\
                 poisson_ratio = {ASPHALT_NU}\n[time]\nfinal_time = 1.0\nsteps = 1\n[[force_control]]\ngroup = \"Base\"\n\
                 component = \"y\"\nforce = \"{equivalent:e}\"\n[contact]\nbound = \"1 - sqrt(1 - x^2)\"\n"
            ),
            "elastic.toml",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let (reference, _) = contact_frames(&elastic);
        let want = &reference.last().unwrap().1;
        let largest = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let off = u.iter().zip(want).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / largest;
        if off > worst.0 {
            worst = (off, *t);
        }
    }
    let (u_first, u_last) = (&creep[1].1, &creep.last().unwrap().1);
    let depth = |u: &Vec<f64>| u.iter().fold(0.0f64, |m, v| m.max(*v));
    eprintln!(
        "asphalt indentation: {} steps, {} factorisation(s); largest u_ν {:.4e} at t = 1e-6 s, {:.4e} at a year; worst \
         {:.2e} of the largest u_ν at t = {:e}",
        stats.steps,
        stats.factorisations,
        depth(u_first),
        depth(u_last),
        worst.0,
        worst.1
    );
    assert!(depth(u_last) > 2.0 * depth(u_first), "it creeps");
    assert!(
        worst.0 < 2e-3,
        "off Lee & Radok by {:.3e} of the largest u_ν at t = {:e}",
        worst.0,
        worst.1
    );
}
