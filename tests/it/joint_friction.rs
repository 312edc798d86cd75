//! Coulomb friction of the ungrouted joints (DESIGN.md §7: sliding block,
//! NAFEMS CGS-4 style contact patch) through the full path — hex8
//! mechanics, joint node pairs, contact solve — with both contact solvers
//! (`active_set` and the condensed cone program `qp`), against closed forms.
//! Poisson's ratio is 0 throughout, so the fields below are exact for the
//! trilinear elements and nothing couples across the loading plane.
//! Forces are read twice: from the joint states, and as support reactions
//! Σ Bᵀσ − f_ext over the prescribed dofs.
//!
//! - Sliding block: block A is fixed, block B (one element layer, 2 × 2
//!   elements over the 4 m × 3 m joint) is pressed into A by its far face
//!   (N = E·A·δ/L) and then sheared by prescribed displacements v of that
//!   face. While it sticks B's stress is uniform and every joint point
//!   carries its closed-form force (shear τ·A_p, normal σ·A_p plus the
//!   edge share of the couple of the shear forces, see [`slide`]); pushed
//!   past μ_s (0.6) at its most loaded point, every point slips with
//!   |r_t| = μ_k·r_n (μ_k = 0.5) and the joint carries T = μ_k·N. Joint
//!   totals, far-face reactions and closed forms agree to 1e-9 (measured:
//!   round-off, ≤ 3e-15). A frictionless joint carries no tangential force;
//!   a μ = 5 joint sticks up to T = 3.9·N.
//! - Patch on an incline: block B rests on a fixed block A across a joint of
//!   slope tan α = 0.1 (the generated mesh rotated), loaded by its own
//!   weight G and pushed horizontally by a prescribed displacement of its
//!   rear face: it sticks, slides from its down-slope end, then slides
//!   everywhere (μ = 0.3). The joint then carries N·(−sin α − μ cos α, 0,
//!   cos α − μ sin α) on B, so the horizontal push F and the vertical load
//!   on the joint satisfy F/(G − V) = (tan α + μ)/(1 − μ tan α) = 0.412371,
//!   with V the vertical reaction of the rear face (see [`incline`] for why
//!   B needs one; V/G = 2.5 % at the onset of sliding). Measured: 1e-15.
//! - Two former defects are pinned: the cone program with a pair component
//!   held by supports (now decoupled and pinned to zero force), and the
//!   active set's slip direction over many sliding steps (now the stick
//!   trial's direction each step, not the last step's slip).

use crate::common;

use std::collections::HashSet;

use common::*;
use groutready::fem::elasticity::{element_dofs, gauss_points, internal_force};
use groutready::mechanics::joints::PointState;
use groutready::mechanics::model::GRAVITY;
use groutready::mechanics::{MechanicsModel, MechanicsSettings, Supports};
use groutready::mesh::{Mesh, Part};
use groutready::scene::{ContactSolverKind, Scene};

const E: f64 = 3.0e10;
/// `[concrete] density_kg_m3` of the common scene.
const DENSITY: f64 = 2400.0;
/// Modulus that is E at any positive age (a = 1e6), ν = 0, no creep.
const MECH: &str = "modulus = { e0_pa = 3.0e10, a = 1.0e6, b = 1.0 }\npoisson = 0.0\n";

const SOLVERS: [(ContactSolverKind, &str); 2] = [
    (ContactSolverKind::ActiveSet, "active_set"),
    (ContactSolverKind::Qp, "qp"),
];

// ---------------------------------------------------------------- helpers

fn scene(effects: &str, geometry: &str, mu_s: f64, mu_k: f64, solver: ContactSolverKind) -> Scene {
    let mut sc = scene_with_concrete(effects, geometry, "", MECH);
    let joints =
        format!("[joints]\nzone_height_m = 3.0\nmu_static = {mu_s}\nmu_kinetic = {mu_k}\n");
    let j: toml::Table = toml::from_str(&joints).unwrap();
    sc.joints = j["joints"].clone().try_into().unwrap();
    sc.solver.contact = solver;
    sc
}

/// Nodes of the elements of `block`, sorted.
fn block_nodes(mesh: &Mesh, block: u32) -> Vec<u32> {
    let mut nodes: Vec<u32> = mesh
        .elements
        .iter()
        .zip(&mesh.parts)
        .filter(|(_, p)| matches!(p, Part::Concrete { block: b, .. } if *b == block))
        .flat_map(|(conn, _)| conn.iter().copied())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// Nodes on side b of the joints.
fn b_side(mesh: &Mesh) -> HashSet<u32> {
    mesh.face_pairs
        .iter()
        .flat_map(|p| p.nodes_a.iter().zip(&p.nodes_b))
        .filter(|(a, b)| a != b)
        .map(|(_, &b)| b)
        .collect()
}

/// Σ Bᵀσ of the live elements minus the accumulated external loads, per
/// global dof: the support reaction on a supported dof away from the joints.
fn reactions(m: &MechanicsModel, mesh: &Mesh) -> Vec<f64> {
    let mut r: Vec<f64> = m.state.f_ext.iter().map(|f| -f).collect();
    for e in (0..mesh.elements.len()).filter(|&e| m.state.live[e]) {
        let g = gauss_points(&mesh.element_coords(e)).unwrap();
        let f = internal_force(&g, &m.state.stress[e]);
        for (k, &d) in element_dofs(&mesh.elements[e]).iter().enumerate() {
            r[d as usize] += f[k];
        }
    }
    r
}

/// Σ over `nodes` of component `comp` of `v` (3 per node).
fn sum_over(v: &[f64], nodes: &[u32], comp: usize) -> f64 {
    nodes.iter().map(|&n| v[3 * n as usize + comp]).sum()
}

/// Totals of the joint forces on side B.
#[derive(Debug, Clone, Copy)]
struct JointTotals {
    /// Σ of the local forces (t1, t2, n)
    local: [f64; 3],
    /// Σ of the global forces
    global: [f64; 3],
    open: usize,
    stick: usize,
    slip: usize,
}

fn joint_totals(m: &MechanicsModel) -> JointTotals {
    let mut t = JointTotals {
        local: [0.0; 3],
        global: [0.0; 3],
        open: 0,
        stick: 0,
        slip: 0,
    };
    for (pt, st) in m.points().iter().zip(&m.state.joints) {
        let g = pt.frame.to_global(st.force);
        t.local = std::array::from_fn(|k| t.local[k] + st.force[k]);
        t.global = std::array::from_fn(|k| t.global[k] + g[k]);
        match st.state {
            PointState::Open => t.open += 1,
            PointState::Stick => t.stick += 1,
            PointState::Slip => t.slip += 1,
            PointState::Grouted => panic!("no grouting here"),
        }
    }
    t
}

// ---------------------------------------------------------- sliding block

/// Block length along x (the joint normal): one element layer [m].
const LB: f64 = 0.1;
/// Block thickness along y, two elements across [m].
const THICK: f64 = 4.0;
const DY: f64 = 2.0;
/// Joint area: thickness × lift height 3 m.
const AREA: f64 = 12.0;
/// Press of the far face into A [m].
const DELTA: f64 = 1.0e-5;

/// One loading step of the sliding block.
#[derive(Debug, Clone)]
struct SlideStep {
    /// τ/σ of the element while the joint sticks: v/(2δ) for ν = 0
    ratio: f64,
    joint: JointTotals,
    /// per joint point: (force on B (t1, t2, n), state, tributary area, y)
    points: Vec<([f64; 3], PointState, f64, f64)>,
    /// reaction of the far face on B
    reaction: [f64; 3],
    /// contact iterations of the step
    iterations: usize,
}

/// Block A (fixed) and block B, one element layer each along x, 2 × 2
/// elements over the 4 m × 3 m joint. B's far face is pressed into A by δ
/// (step 0), then sheared to v = 2δ·ratio along +y (one step per ratio).
///
/// Both faces of B's element layer are then imposed (the joint face by the
/// stuck contact), so its field is linear in x and its stress uniform:
/// σ_xx = −σ = −E·δ/L, τ_xy = τ = G·v/L with G = E/2. The joint point p of
/// tributary area A_p carries (t1, t2, n) = (−τ·A_p, 0, σ·A_p + e_p·τ·a_p):
/// the shear τ on the free faces y = 0 and y = 4 m is carried by their edge
/// nodes as normal forces, a_p = A_p·L/Δy, e_p = −1 at y = 0, +1 at y = 4 m
/// (the couple of the two shear forces T = τ·A at distance L).
fn slide(solver: ContactSolverKind, mu_s: f64, mu_k: f64, ratios: &[f64]) -> Vec<SlideStep> {
    let geometry = blocks_geometry(2, LB, THICK, 1, 1, 2) + "layers_per_lift = 2\n";
    let sc = scene("\"joints\"", &geometry, mu_s, mu_k, solver);
    let mesh = blocks_mesh(&sc);
    let far: Vec<u32> = (0..mesh.nodes.len() as u32)
        .filter(|&n| (mesh.nodes[n as usize][0] - 2.0 * LB).abs() < 1e-12)
        .collect();
    let mut fixed = vec![];
    for &n in block_nodes(&mesh, 1).iter().chain(&far) {
        fixed.extend((0..3).map(|c| (n, c)));
    }
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &Supports { fixed }).unwrap();
    assert_eq!(m.points().len(), 9, "3 × 3 joint points");
    for p in m.points() {
        assert_eq!(
            (p.frame.t1, p.frame.t2, p.frame.n),
            ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
            "joint frame"
        );
    }
    m.pour(1, 1, 0.0);
    m.pour(2, 1, 0.0);
    let mut out = Vec::new();
    let mut v_old = 0.0;
    for (k, &ratio) in std::iter::once(&0.0).chain(ratios).enumerate() {
        let (comp, increment) = if k == 0 {
            (0, -DELTA)
        } else {
            let v = 2.0 * DELTA * ratio;
            let dv = v - v_old;
            v_old = v;
            (1, dv)
        };
        for &n in &far {
            m.prescribe(n, comp, increment).unwrap();
        }
        let before = m.stats.contact_iterations;
        m.step(k as f64, k as f64 + 1.0, None, None)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        let r = reactions(&m, &mesh);
        out.push(SlideStep {
            ratio,
            joint: joint_totals(&m),
            points: m
                .points()
                .iter()
                .zip(&m.state.joints)
                .map(|(p, st)| (st.force, st.state, p.area, mesh.nodes[p.a as usize][1]))
                .collect(),
            reaction: std::array::from_fn(|c| sum_over(&r, &far, c)),
            iterations: m.stats.contact_iterations - before,
        });
    }
    out
}

/// Checks every step of [`slide`] against the closed forms (see there):
/// while the joint sticks (ratio ≤ `stick_up_to`, never slipped) every point
/// sticks and carries its closed-form force; once pushed past static
/// friction every point slips with |r_t| = μ_k·r_n along −t1, and the joint
/// carries T = μ_k·N in total. N = σ·A throughout (the edge terms cancel).
/// The far face carries the opposite of the joint (support reactions).
fn check_slide(name: &str, mu_s: f64, mu_k: f64, stick_up_to: f64, steps: &[SlideStep]) {
    let sigma = E * DELTA / LB;
    let n_total = sigma * AREA;
    let tol = 1e-9;
    let mut slipped = false;
    for (k, s) in steps.iter().enumerate() {
        let j = &s.joint;
        let what = |q: &str| {
            format!(
                "{name}, μ_s {mu_s}, μ_k {mu_k}, step {k} (ratio {}): {q}",
                s.ratio
            )
        };
        slipped |= s.ratio > stick_up_to || mu_s == 0.0;
        let t_total = if slipped {
            mu_k * n_total
        } else {
            s.ratio * n_total
        };
        assert_eq!(j.open, 0, "{}", what("no point opens"));
        assert_eq!(
            if slipped { j.slip } else { j.stick },
            9,
            "{}",
            what(if slipped {
                "every point slips"
            } else {
                "every point sticks"
            })
        );
        let close = |got: f64, want: f64, scale: f64, q: &str| {
            let err = (got - want).abs() / scale;
            assert!(
                err <= tol,
                "{}: got {got:e}, want {want:e}, error {err:e}",
                what(q)
            );
            err
        };
        // Totals: the joint pushes B along +x and holds it back along −y.
        let mut worst: f64 = 0.0;
        worst = worst.max(close(j.local[2], n_total, n_total, "Σ normal force"));
        worst = worst.max(close(-j.local[0], t_total, n_total, "Σ tangential force"));
        worst = worst.max(close(j.local[1], 0.0, n_total, "Σ t2 force"));
        worst = worst.max(close(
            -s.reaction[0],
            n_total,
            n_total,
            "far-face reaction x",
        ));
        worst = worst.max(close(
            s.reaction[1],
            t_total,
            n_total,
            "far-face reaction y",
        ));
        worst = worst.max(close(s.reaction[2], 0.0, n_total, "far-face reaction z"));
        // Points.
        let tau = s.ratio * sigma;
        let mut most_loaded: f64 = 0.0;
        for (p, &(f, state, area, y)) in s.points.iter().enumerate() {
            let q = |c: &str| format!("point {p} (y {y}) {c}");
            if slipped {
                assert_eq!(state, PointState::Slip, "{}", what(&q("state")));
                worst = worst.max(close(-f[0], mu_k * f[2], f[2], &q("|r_t| = μ_k r_n")));
                worst = worst.max(close(f[1], 0.0, f[2], &q("t2 force")));
            } else {
                assert_eq!(state, PointState::Stick, "{}", what(&q("state")));
                let edge = if y < 1e-9 {
                    -1.0
                } else if y > THICK - 1e-9 {
                    1.0
                } else {
                    0.0
                };
                let want = [-tau * area, 0.0, sigma * area + edge * tau * area * LB / DY];
                for c in 0..3 {
                    worst = worst.max(close(f[c], want[c], sigma * area, &q("closed-form force")));
                }
            }
            most_loaded = most_loaded.max(-f[0] / f[2]);
        }
        eprintln!(
            "sliding block {name} μ_s {mu_s} μ_k {mu_k} step {k}: ratio {:.2}, T/N = {:.12} \
             (want {:.3}), most loaded point |r_t|/r_n {most_loaded:.4}, worst error {worst:.1e}, \
             stick {} slip {}, {} passes",
            s.ratio,
            -j.local[0] / j.local[2],
            t_total / n_total,
            j.stick,
            j.slip,
            s.iterations
        );
    }
}

#[test]
fn sliding_block_sticks_below_static_friction_then_slips_at_kinetic_friction() {
    // The most loaded point (y = 0) reaches μ_s = 0.6 at ratio 0.6/1.03 =
    // 0.5825; at 0.75 even the least loaded one (0.75/1.0375 = 0.72) is
    // past it. Every later increment (0.15) exceeds μ_s − μ_k.
    let ratios = [0.15, 0.3, 0.45, 0.55, 0.75, 0.9, 1.05];
    for (solver, name) in SOLVERS {
        let steps = slide(solver, 0.6, 0.5, &ratios);
        check_slide(name, 0.6, 0.5, 0.55, &steps);
    }
}

#[test]
fn frictionless_joint_carries_no_tangential_force() {
    for (solver, name) in SOLVERS {
        let steps = slide(solver, 0.0, 0.0, &[0.2, 0.5]);
        check_slide(name, 0.0, 0.0, 0.0, &steps);
    }
}

#[test]
fn high_friction_joint_sticks() {
    // The most loaded point reaches μ = 5 at ratio 5/1.25 = 4.
    for (solver, name) in SOLVERS {
        let steps = slide(solver, 5.0, 5.0, &[0.5, 1.5, 3.0, 3.9]);
        check_slide(name, 5.0, 5.0, 5.0, &steps);
    }
}

// -------------------------------------------------------------- incline

const TAN_ALPHA: f64 = 0.1;
const MU: f64 = 0.3;

/// How block B of [`incline`] is held across the slope (global Y = −t1).
#[derive(Debug, Clone, Copy, PartialEq)]
enum HoldY {
    /// the rear face is held in Y (its reaction is zero for ν = 0)
    RearFace,
    /// the joint nodes of B are held in Y with those of A: t1 of every
    /// pair is a supported relative component
    Joint,
}

/// What the incline run measured after one step.
#[derive(Debug, Clone)]
struct InclineStep {
    joint: JointTotals,
    /// per joint point: force on B (t1, t2, n), state
    points: Vec<([f64; 3], PointState)>,
    /// reaction of the rear face on B (global)
    reaction: [f64; 3],
    iterations: usize,
}

/// Block B (1 m high, 1 m across, 3 m along the slope; 2 × 2 × 3 elements)
/// on a fixed block A across a joint rising along +X with slope tan α: the
/// generated two-block mesh rotated by x ↦ n = (−sin α, 0, cos α), y ↦ −Y,
/// z ↦ (cos α, 0, sin α), so the joint frame is t1 = −Y, t2 up the slope.
///
/// B's own weight G is applied in step 0, then its rear face (the down-slope
/// end, z = 0 before the rotation, less the joint nodes) is pushed along +X
/// by `push[k]` in step k + 1. The rear face is also held vertically:
/// every pair starts open, so without a vertical support B would float and
/// the step's stiffness, which both solvers factorise before any contact,
/// would be singular. Its vertical reaction V is measured, and the joint
/// carries the vertical load G − V.
fn incline(solver: ContactSolverKind, hold: HoldY, push: &[f64]) -> (Vec<InclineStep>, f64) {
    let geometry = blocks_geometry(2, 1.0, 1.0, 1, 2, 2) + "layers_per_lift = 3\n";
    let sc = scene("\"self_weight\", \"joints\"", &geometry, MU, MU, solver);
    let mut mesh = blocks_mesh(&sc);
    let b_nodes = b_side(&mesh);
    let rear: Vec<u32> = block_nodes(&mesh, 2)
        .into_iter()
        .filter(|n| mesh.nodes[*n as usize][2].abs() < 1e-12 && !b_nodes.contains(n))
        .collect();
    let c = 1.0 / (1.0 + TAN_ALPHA * TAN_ALPHA).sqrt();
    let s = TAN_ALPHA * c;
    for p in &mut mesh.nodes {
        let [x, y, z] = *p;
        *p = [-s * x + c * z, -y, c * x + s * z];
    }
    let mut fixed = vec![];
    for n in block_nodes(&mesh, 1) {
        fixed.extend((0..3).map(|c| (n, c)));
    }
    for &n in &rear {
        fixed.extend([0, 2].map(|c| (n, c)));
        if hold == HoldY::RearFace {
            fixed.push((n, 1));
        }
    }
    if hold == HoldY::Joint {
        fixed.extend(b_nodes.iter().map(|&n| (n, 1)));
    }
    let mechanics = MechanicsSettings::from_scene(&sc).unwrap();
    let mut m = MechanicsModel::new(&mesh, &mechanics, &Supports { fixed }).unwrap();
    assert_eq!(m.points().len(), 12, "3 × 4 joint points");
    for p in m.points() {
        let f = &p.frame;
        let want = [[0.0, -1.0, 0.0], [c, 0.0, s], [-s, 0.0, c]];
        for (axis, w) in [f.t1, f.t2, f.n].iter().zip(&want) {
            assert!(
                (0..3).all(|k| (axis[k] - w[k]).abs() < 1e-12),
                "frame {f:?}"
            );
        }
    }
    m.pour(1, 1, 0.0);
    m.pour(2, 1, 0.0);
    let mut out = Vec::new();
    for (k, &dx) in std::iter::once(&0.0).chain(push).enumerate() {
        for &n in &rear {
            m.prescribe(n, 0, dx).unwrap();
        }
        let before = m.stats.contact_iterations;
        m.step(k as f64, k as f64 + 1.0, None, None)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        let r = reactions(&m, &mesh);
        out.push(InclineStep {
            joint: joint_totals(&m),
            points: m
                .state
                .joints
                .iter()
                .map(|st| (st.force, st.state))
                .collect(),
            reaction: std::array::from_fn(|c| sum_over(&r, &rear, c)),
            iterations: m.stats.contact_iterations - before,
        });
    }
    let weight = DENSITY * GRAVITY * 3.0;
    let f_ext_b = sum_over(&m.state.f_ext, &block_nodes(&mesh, 2), 2);
    assert_rel(-f_ext_b, weight, 1e-12, "self-weight of B");
    (out, weight)
}

/// Checks every step of [`incline`]: equilibrium of B (rear-face reactions,
/// joint forces, weight), no force across the slope, the friction law at
/// every point, F/(G − V) below the limit while a point sticks and equal to
/// it once every point slides; the last step must have every point sliding.
fn check_incline(name: &str, steps: &[InclineStep], g: f64) {
    let limit = (TAN_ALPHA + MU) / (1.0 - MU * TAN_ALPHA);
    let tol = 1e-9;
    let mut worst_limit: f64 = 0.0;
    for (k, s) in steps.iter().enumerate() {
        let what = |q: &str| format!("{name}, step {k}: {q}");
        let (f, v) = (s.reaction[0], s.reaction[2]);
        let ratio = f / (g - v);
        let j = &s.joint;
        for c in 0..3 {
            let weight = if c == 2 { -g } else { 0.0 };
            let residual = s.reaction[c] + j.global[c] + weight;
            assert!(
                residual.abs() <= tol * g,
                "{}",
                what(&format!("equilibrium of B, component {c}: {residual:e} N"))
            );
        }
        assert!(
            s.reaction[1].abs() <= tol * g,
            "{}",
            what(&format!("reaction across the slope {:e} N", s.reaction[1]))
        );
        assert_eq!(j.open, 0, "{}", what("no point opens"));
        for (p, &(r, state)) in s.points.iter().enumerate() {
            let q = |c: &str| what(&format!("point {p}: {c} (force {r:?}, {state:?})"));
            assert!(
                r[0].abs() <= tol * r[2],
                "{}",
                q("no friction across the slope")
            );
            match state {
                PointState::Stick => {
                    assert!(-r[1] <= MU * r[2] * (1.0 + tol), "{}", q("inside the cone"))
                }
                PointState::Slip => {
                    assert!(
                        (-r[1] - MU * r[2]).abs() <= tol * r[2],
                        "{}",
                        q("on the cone, down the slope")
                    )
                }
                _ => panic!("{}", q("state")),
            }
        }
        let err = rel(ratio, limit);
        if j.stick == 0 {
            assert!(
                err <= tol,
                "{}",
                what(&format!(
                    "F/(G − V) = {ratio:.12} vs {limit:.12}, error {err:e}"
                ))
            );
            worst_limit = worst_limit.max(err);
        } else {
            assert!(
                ratio <= limit * (1.0 + tol),
                "{}",
                what(&format!(
                    "F/(G − V) = {ratio} above the limit while sticking"
                ))
            );
        }
        eprintln!(
            "patch {name} step {k}: F/(G − V) = {ratio:.12} (F/G {:.6}, V/G {:+.4}), \
             error {err:.1e}, stick {} slip {}, {} passes, reaction across {:.1e} N",
            f / g,
            v / g,
            j.stick,
            j.slip,
            s.iterations,
            s.reaction[1]
        );
    }
    let last = &steps.last().unwrap().joint;
    assert_eq!(last.slip, 12, "{name}: every point slides at the last push");
    eprintln!("patch {name}: limit {limit:.9}, worst error once sliding {worst_limit:.1e}");
}

#[test]
fn patch_on_incline_slides_at_the_closed_form_push() {
    assert_eq!(
        format!("{:.6}", (TAN_ALPHA + MU) / (1.0 - MU * TAN_ALPHA)),
        "0.412371"
    );
    for (solver, name) in SOLVERS {
        // Sticks, slides from the down-slope end (partial slip), then slides
        // everywhere from the fourth push (2 µm).
        let (steps, g) = incline(solver, HoldY::RearFace, &[5e-7; 6]);
        check_incline(name, &steps, g);
    }
}

#[test]
fn patch_on_incline_held_across_the_slope_at_the_joint_active_set() {
    let (steps, g) = incline(ContactSolverKind::ActiveSet, HoldY::Joint, &[5e-7; 6]);
    check_incline("active_set, joint held in Y", &steps, g);
}

/// The supported relative components (t1 of every pair) are not contact
/// unknowns of the cone program (they used to enter it with a compliance of
/// 1 m/N, and its friction fixed point did not converge).
#[test]
fn patch_on_incline_held_across_the_slope_at_the_joint_qp() {
    let (steps, g) = incline(ContactSolverKind::Qp, HoldY::Joint, &[5e-7; 6]);
    check_incline("qp, joint held in Y", &steps, g);
}

/// Sixteen more steps of steady sliding (1 µm each).
fn long_slide(solver: ContactSolverKind, name: &str) {
    let (steps, g) = incline(solver, HoldY::RearFace, &[1e-6; 18]);
    check_incline(name, &steps, g);
}

#[test]
fn patch_on_incline_keeps_sliding_up_the_slope_qp() {
    long_slide(ContactSolverKind::Qp, "qp, long slide");
}

/// Each step's friction direction is the stick trial's: taken from the
/// previous step's slip, a component across the slope grew by a factor ≈ −20
/// per step (1 µm steps) from round-off until F/(G − V) was off by 1 %.
#[test]
fn patch_on_incline_keeps_sliding_up_the_slope_active_set() {
    long_slide(ContactSolverKind::ActiveSet, "active_set, long slide");
}
