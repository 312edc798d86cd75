//! `[boundary]`: what holds the model's far faces (the rock's bottom and
//! sides, or the base of a rock-less model), per side.
//!
//! ```toml
//! [boundary.base]
//! temperature_c = 14.0     # a fixed temperature; absent = adiabatic
//! support = "fixed"        # "fixed", "rollers" or "free"
//! [boundary.upstream]
//! support = "rollers"
//! ```
//!
//! Sides are `base`, `upstream`, `downstream`, `left_bank`, `right_bank`;
//! which far face is on which side is [`crate::mesh::far`]'s geometric
//! rule. Defaults (no `[boundary]` table): every side adiabatic and fixed,
//! the behaviour of scenes written before the table existed.

use serde::{Deserialize, Serialize};

use crate::mesh::FarSide;

/// Mechanical support of a far side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Support {
    /// All three displacement components zero (default).
    #[default]
    Fixed,
    /// The displacement normal to the face zero, free along it; needs
    /// faces normal to x, y or z.
    Rollers,
    /// No support.
    Free,
}

impl Support {
    pub fn name(self) -> &'static str {
        match self {
            Support::Fixed => "fixed",
            Support::Rollers => "rollers",
            Support::Free => "free",
        }
    }
}

/// One far side's conditions.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FarFace {
    /// Fixed temperature of the side's nodes [°C] (a Dirichlet condition
    /// from the first thermal step); absent = adiabatic (default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<f64>,
    /// `fixed` (default), `rollers` or `free`.
    pub support: Support,
}

/// `[boundary]`: one [`FarFace`] per side.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Boundary {
    pub base: FarFace,
    pub upstream: FarFace,
    pub downstream: FarFace,
    pub left_bank: FarFace,
    pub right_bank: FarFace,
}

impl Boundary {
    /// The conditions of `side`.
    pub fn side(&self, side: FarSide) -> &FarFace {
        match side {
            FarSide::Base => &self.base,
            FarSide::Upstream => &self.upstream,
            FarSide::Downstream => &self.downstream,
            FarSide::LeftBank => &self.left_bank,
            FarSide::RightBank => &self.right_bank,
        }
    }

    /// Every side adiabatic and fixed (a scene without `[boundary]`).
    pub fn is_default(&self) -> bool {
        *self == Boundary::default()
    }

    /// The fixed temperature of each side, in [`FarSide::ALL`] order.
    pub fn temperatures(&self) -> [Option<f64>; 5] {
        FarSide::ALL.map(|s| self.side(s).temperature_c)
    }

    /// The support of each side, in [`FarSide::ALL`] order.
    pub fn supports(&self) -> [Support; 5] {
        FarSide::ALL.map(|s| self.side(s).support)
    }
}
