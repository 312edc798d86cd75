//! `[solver] preset = "fast" | "standard" | "reference"`: a named set of the
//! time-stepping keys that trade accuracy for time, chosen from the front
//! `groutready study accuracy` measures (README, "Accuracy and presets").
//! A key written in the scene overrides its preset's value; the values are
//! applied when the scene text is read ([`apply`]), so a run folder's
//! `scene.json` holds the settings as run.
//!
//! Verified by `tests/it/study_accuracy.rs` (a preset's values, and an
//! explicit key beating its preset).

use serde::{Deserialize, Serialize};

use super::{CapacityKind, ScheduledStep, TimeStepping};

/// A named accuracy level of the time stepping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// first step 0.5 d doubling to 8 d, lumped capacity, backward Euler.
    Fast,
    /// first step 0.25 d doubling to 4 d, lumped capacity, backward Euler
    /// (the keys' defaults).
    Standard,
    /// 0.1 d steps for 2 days after each pour, 0.25 d to day 7, then 1 d;
    /// consistent capacity, backward Euler.
    Reference,
}

impl Preset {
    pub const ALL: [Preset; 3] = [Preset::Fast, Preset::Standard, Preset::Reference];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Fast => "fast",
            Preset::Standard => "standard",
            Preset::Reference => "reference",
        }
    }

    /// The `[time]` table this preset stands for (every key it sets; the
    /// others at their defaults).
    pub fn time(self) -> TimeStepping {
        let d = TimeStepping::default();
        match self {
            Preset::Fast => TimeStepping {
                first_step_days: 0.5,
                max_step_days: 8.0,
                ..d
            },
            Preset::Standard => d,
            Preset::Reference => TimeStepping {
                first_step_days: 0.1,
                max_step_days: 1.0,
                step_schedule: vec![
                    ScheduledStep {
                        step_days: 0.1,
                        until_days: 2.0,
                    },
                    ScheduledStep {
                        step_days: 0.25,
                        until_days: 7.0,
                    },
                ],
                capacity: CapacityKind::Consistent,
                ..d
            },
        }
    }
}

/// The `[time]` keys a preset sets.
pub const PRESET_KEYS: [&str; 6] = [
    "first_step_days",
    "growth",
    "max_step_days",
    "step_schedule",
    "theta",
    "capacity",
];

/// Sets every key of `preset` that `written` (the keys of the scene's
/// `[time]` table) does not name.
pub fn apply(preset: Preset, time: &mut TimeStepping, written: &dyn Fn(&str) -> bool) {
    let p = preset.time();
    for key in PRESET_KEYS.into_iter().filter(|k| !written(k)) {
        match key {
            "first_step_days" => time.first_step_days = p.first_step_days,
            "growth" => time.growth = p.growth,
            "max_step_days" => time.max_step_days = p.max_step_days,
            "step_schedule" => time.step_schedule = p.step_schedule.clone(),
            "theta" => time.theta = p.theta,
            _ => time.capacity = p.capacity,
        }
    }
}
