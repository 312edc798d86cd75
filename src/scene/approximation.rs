//! The opt-in approximations of the mechanics, and the exact path.
//!
//! Every setting that trades accuracy for time is off by default; a scene
//! that turns one on plans a different dam, by an amount `groutready study
//! compare` measures against the exact run (the large arch's five together:
//! its deciding apertures within 0.390 mm, the remedies near the 0.5 mm
//! limit different, docs/PERFORMANCE.md). So the reports say which ones a
//! result was computed with ([`Scene::approximations`]), and the studies
//! compare a scene with its exact path ([`Scene::exact_path`]) from this one
//! list, which a new approximation joins.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::Scene;

/// One opt-in approximation a scene turns on, with its setting's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Approximation {
    /// `time.mechanics_max_step_days` above 1: mechanical steps of up to
    /// that many days between events.
    LongerSteps { max_days: u32 },
    /// `time.mechanics_merge_pours`: pours inside the longer steps.
    MergedPours,
    /// `time.mechanics_merge_groutings`: groutings at the longer steps'
    /// starts.
    MergedGroutings,
    /// `solver.layer_merging_age_days` above 0: old lifts tied into thicker
    /// element layers.
    LayerMerging { age_days: u32 },
    /// `solver.rock_coarsening` above 1: every N-th node level of the rock
    /// kept.
    RockCoarsening { every: u32 },
}

impl Approximation {
    /// The scene key that turns it on.
    pub fn key(self) -> &'static str {
        match self {
            Approximation::LongerSteps { .. } => "time.mechanics_max_step_days",
            Approximation::MergedPours => "time.mechanics_merge_pours",
            Approximation::MergedGroutings => "time.mechanics_merge_groutings",
            Approximation::LayerMerging { .. } => "solver.layer_merging_age_days",
            Approximation::RockCoarsening { .. } => "solver.rock_coarsening",
        }
    }

    /// Turns it on in `scene`: the one place a study writes the setting,
    /// the inverse of [`Scene::approximations`]. Merged pours and groutings
    /// need longer steps to merge into; they do not turn them on.
    pub fn turn_on(self, scene: &mut Scene) {
        let (t, s) = (&mut scene.time, &mut scene.solver);
        match self {
            Approximation::LongerSteps { max_days } => t.mechanics_max_step_days = max_days,
            Approximation::MergedPours => t.mechanics_merge_pours = true,
            Approximation::MergedGroutings => t.mechanics_merge_groutings = true,
            Approximation::LayerMerging { age_days } => s.layer_merging_age_days = age_days,
            Approximation::RockCoarsening { every } => s.rock_coarsening = every,
        }
    }
}

/// `key = value`, as written in the scene.
impl fmt::Display for Approximation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let key = self.key();
        match *self {
            Approximation::LongerSteps { max_days: n }
            | Approximation::LayerMerging { age_days: n }
            | Approximation::RockCoarsening { every: n } => write!(f, "{key} = {n}"),
            Approximation::MergedPours | Approximation::MergedGroutings => {
                write!(f, "{key} = true")
            }
        }
    }
}

/// The approximations in words for a report line: "none (the exact path)"
/// or the `key = value` list.
pub fn describe(approximations: &[Approximation]) -> String {
    if approximations.is_empty() {
        return "none (the exact path)".into();
    }
    approximations
        .iter()
        .map(Approximation::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

impl Scene {
    /// The opt-in approximations this scene turns on (empty: its mechanics
    /// is exact), in the order of the scene's keys.
    pub fn approximations(&self) -> Vec<Approximation> {
        let (t, s) = (&self.time, &self.solver);
        let mut out = Vec::new();
        if t.mechanics_max_step_days > 1 {
            out.push(Approximation::LongerSteps {
                max_days: t.mechanics_max_step_days,
            });
        }
        if t.mechanics_merge_pours {
            out.push(Approximation::MergedPours);
        }
        if t.mechanics_merge_groutings {
            out.push(Approximation::MergedGroutings);
        }
        if s.layer_merging_age_days > 0 {
            out.push(Approximation::LayerMerging {
                age_days: s.layer_merging_age_days,
            });
        }
        if s.rock_coarsening > 1 {
            out.push(Approximation::RockCoarsening {
                every: s.rock_coarsening,
            });
        }
        out
    }

    /// This scene without its approximations (the same dam, the same
    /// accelerations that are exact to round-off).
    pub fn without_approximations(&self) -> Scene {
        let mut s = self.clone();
        s.time.mechanics_max_step_days = 1;
        s.time.mechanics_merge_pours = false;
        s.time.mechanics_merge_groutings = false;
        s.solver.layer_merging_age_days = 0;
        s.solver.rock_coarsening = 1;
        s
    }

    /// The exact path ISSUE 12's fast paths are held to: no approximation,
    /// and none of the accelerations that are exact only to round-off or to
    /// the contact iteration's tolerance either: a factorisation at every
    /// contact-set change (`solver.contact_capacitance = false`, which also
    /// makes no factor ahead) and the whole rock in every step
    /// (`solver.condense_rock = false`).
    pub fn exact_path(&self) -> Scene {
        let mut s = self.without_approximations();
        s.solver.contact_capacitance = false;
        s.solver.condense_rock = false;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        Scene::load(&root.join("models/small_dam_joints.toml")).unwrap()
    }

    #[test]
    fn every_approximation_is_listed_and_cleared() {
        let mut s = scene();
        assert!(s.approximations().is_empty());
        s.time.mechanics_max_step_days = 3;
        s.time.mechanics_merge_pours = true;
        s.time.mechanics_merge_groutings = true;
        s.solver.layer_merging_age_days = 60;
        s.solver.rock_coarsening = 4;
        let listed = s.approximations();
        assert_eq!(listed.len(), 5);
        assert_eq!(
            describe(&listed),
            "time.mechanics_max_step_days = 3, time.mechanics_merge_pours = true, \
             time.mechanics_merge_groutings = true, solver.layer_merging_age_days = 60, \
             solver.rock_coarsening = 4"
        );
        let exact = s.without_approximations();
        assert!(exact.approximations().is_empty());
        // nothing else changed: the scene's own defaults come back
        assert_eq!(exact, scene());
        assert_eq!(describe(&[]), "none (the exact path)");
    }

    /// Each approximation turned on alone is listed alone, with its value.
    #[test]
    fn turning_one_on_lists_it() {
        for a in [
            Approximation::LongerSteps { max_days: 3 },
            Approximation::MergedPours,
            Approximation::MergedGroutings,
            Approximation::LayerMerging { age_days: 60 },
            Approximation::RockCoarsening { every: 4 },
        ] {
            let mut s = scene();
            a.turn_on(&mut s);
            assert_eq!(s.approximations(), [a]);
            assert_eq!(s.without_approximations(), scene());
        }
    }

    #[test]
    fn the_exact_path_refactorises_and_keeps_the_whole_rock() {
        let s = scene();
        assert!(s.solver.contact_capacitance && s.solver.condense_rock);
        let exact = s.exact_path();
        assert!(!exact.solver.contact_capacitance && !exact.solver.condense_rock);
        assert!(exact.approximations().is_empty());
        assert_eq!(exact.exact_path(), exact);
    }
}
