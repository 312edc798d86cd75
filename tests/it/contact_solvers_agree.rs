//! The two contact solvers behind one interface (DESIGN.md §4) agree on a
//! shared staged scene: the small dam with joints (five blocks, pipe cooling,
//! creep, self-weight), its first 100 days, solved once with the active set
//! and once with the condensed cone program (clarabel). Compared: the daily
//! aperture history of every zone point and zone minimum, and the states.
//!
//! Frictionless, both solve the same complementarity problem and agree to
//! round-off (measured 1.7e-15 mm). With friction (one coefficient) they
//! differ by 1.6e-3 of the widest aperture over 100 days. The likely cause,
//! not yet proven: within a step the active set keeps the direction of the
//! stick trial force (a return mapping), the cone program takes the
//! direction of maximum dissipation (opposite the slip), and the two differ
//! where a joint's tangential compliance is not isotropic.

use std::path::Path;

use groutready::app;
use groutready::scene::ContactSolverKind;
use groutready::sim::{JointSample, Simulation};

type History = Vec<(groutready::vocab::Day, Vec<Option<JointSample>>)>;

fn run(contact: ContactSolverKind, mu: f64, days: i64) -> History {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut inputs = app::load_inputs(&root.join("models/small_dam_joints.toml"), None).unwrap();
    inputs.scene.solver.contact = contact;
    // One friction coefficient: with μ_s > μ_k the cone program retries the
    // static limit on a point that slid in the step before, the active set
    // keeps it sliding at the kinetic one (both are admissible).
    inputs.scene.joints.mu_static = mu;
    inputs.scene.joints.mu_kinetic = mu;
    let mut sim = Simulation::new(&inputs.scene, &inputs.mesh, &inputs.schedules).unwrap();
    sim.timeline.end_day = groutready::vocab::Day(days);
    sim.run(None, &mut |_, _| {}).unwrap();
    sim.joint_records.rows
}

/// Largest aperture difference relative to the widest aperture, and the
/// number of differing states, over the whole history.
fn compare(mu: f64, days: i64) -> (f64, usize, usize) {
    let a = run(ContactSolverKind::ActiveSet, mu, days);
    let q = run(ContactSolverKind::Qp, mu, days);
    assert_eq!(a.len(), q.len());
    let (mut widest, mut diff, mut samples, mut closed, mut differ) = (0.0f64, 0.0f64, 0, 0, 0);
    for ((da, ra), (dq, rq)) in a.iter().zip(&q) {
        assert_eq!(da, dq);
        for (sa, sq) in ra.iter().zip(rq) {
            match (sa, sq) {
                (Some(sa), Some(sq)) => {
                    samples += 1;
                    widest = widest.max(sa.aperture.abs());
                    diff = diff.max((sa.aperture - sq.aperture).abs());
                    closed += usize::from(sa.state != groutready::vocab::JointState::Open);
                    differ += usize::from(sa.state != sq.state);
                }
                (None, None) => {}
                _ => panic!("day {da}: a zone exists in one run only"),
            }
        }
    }
    eprintln!(
        "μ = {mu}, {days} days: {samples} samples ({closed} closed), widest aperture {:.4} mm, \
         apertures differ by at most {:.2e} mm, {differ} states differ",
        1e3 * widest,
        1e3 * diff
    );
    assert!(
        samples > 1000 && closed > 20 && widest > 1e-4,
        "the joints close and open"
    );
    (diff / widest, differ, samples)
}

#[test]
fn frictionless_the_two_solvers_agree_to_round_off() {
    let (rel, differ, _) = compare(0.0, 100);
    assert!(rel < 1e-8, "apertures differ by {rel:.2e} of the widest");
    assert_eq!(differ, 0);
}

#[test]
fn with_friction_they_agree_within_half_a_percent_of_the_widest_aperture() {
    let (rel, differ, samples) = compare(0.5, 100);
    assert!(rel < 5e-3, "apertures differ by {rel:.2e} of the widest");
    // Labels of points whose tangential force sits at the friction limit
    // (stick at the limit vs slip) follow round-off: 5 to 11 of 1,096 were
    // measured, varying with how the tests share the threads.
    assert!(
        differ <= samples / 50,
        "{differ} of {samples} states differ"
    );
}
