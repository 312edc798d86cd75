//! Contact points of the ungrouted transverse joints.
//!
//! One point per pair of duplicated joint nodes (a on block j, b on block
//! j+1); its normal n points from A to B (area-weighted over the joint quads
//! around it) and its tributary area is a quarter of each adjacent quad.
//! Points where a joint touches rock share one node and carry no contact.
//! The gap of a point starts at the scene's initial gap when both of its
//! nodes first exist (the later block is cast against the earlier one).

use serde::{Deserialize, Serialize};

use crate::fem::quad4;
use crate::joint::{ContactError, ContactState, LocalFrame};
use crate::mesh::Mesh;
use crate::vocab::JointState;

/// Geometry of one contact point.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPoint {
    pub joint: u32,
    pub zone: u32,
    pub a: u32,
    pub b: u32,
    pub frame: LocalFrame,
    /// tributary area \[m²\]
    pub area: f64,
}

/// Checkpointable state of one joint point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct JointPointState {
    /// both nodes exist
    pub paired: bool,
    /// Normal opening \[m\]. Before grouting: the contact gap (≥ 0 up to solver
    /// tolerance). After grouting: the opening since grouting (negative when
    /// the grout layer is compressed; ≥ 0 again once the layer has cracked).
    pub gap: f64,
    /// total force on side B in the local frame (t1, t2, n) \[N\]; n > 0 presses
    pub force: [f64; 3],
    pub state: PointState,
    /// direction (t1, t2) of the friction force while the point slips
    pub slip_dir: [f64; 2],
    /// the grout layer, from the zone's grouting date
    pub grout: Option<Grout>,
}

impl JointPointState {
    pub const UNPAIRED: JointPointState = JointPointState {
        paired: false,
        gap: 0.0,
        force: [0.0; 3],
        state: PointState::Open,
        slip_dir: [0.0; 2],
        grout: None,
    };

    /// Joint opening a joint meter set at the pour would read \[m\]: the gap
    /// before grouting, the aperture grouted plus the opening since after.
    pub fn aperture(&self) -> f64 {
        match &self.grout {
            None => self.gap,
            Some(g) => g.aperture + self.gap,
        }
    }

    /// The state the tables report (a cracked grout layer is `Reopened`).
    pub fn label(&self) -> JointState {
        match (&self.grout, self.state) {
            (Some(g), _) if g.cracked_day.is_some() => JointState::Reopened,
            (_, PointState::Grouted) => JointState::Grouted,
            (_, PointState::Open) => JointState::Open,
            (_, PointState::Stick) => JointState::Stick,
            (_, PointState::Slip) => JointState::Slip,
        }
    }
}

/// The thin grout layer of a grouted point (the paper's eqs. 19–29): its
/// reference is the deformed geometry at grouting, it carries the contact
/// force of that moment as initial force, and its stiffness is
/// area·diag(G, G, E)/t.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grout {
    pub day: f64,
    /// aperture filled by the grout \[m\]
    pub aperture: f64,
    /// layer thickness: the aperture, at least the scene's floor \[m\]
    pub thickness: f64,
    /// spring of the point in the local frame (t1, t2, n) [N/m]
    pub stiffness: [f64; 3],
    /// day the layer cracked in tension (then the point is a contact again)
    pub cracked_day: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PointState {
    Open,
    Stick,
    Slip,
    /// bonded grout layer (intact)
    Grouted,
}

impl PointState {
    pub fn is_closed(self) -> bool {
        matches!(self, PointState::Stick | PointState::Slip)
    }
}

impl From<ContactState> for PointState {
    fn from(s: ContactState) -> Self {
        match s {
            ContactState::Open => PointState::Open,
            ContactState::Stick => PointState::Stick,
            ContactState::Slip => PointState::Slip,
        }
    }
}

/// The contact points of every joint of the mesh.
pub fn build_points(mesh: &Mesh) -> Result<Vec<JointPoint>, ContactError> {
    use std::collections::BTreeMap;
    /// What the quads around one node pair contribute to its point.
    struct Sum {
        joint: u32,
        zone: u32,
        /// Σ area-weighted unit normal
        normal: [f64; 3],
        area: f64,
    }
    let mut acc: BTreeMap<(u32, u32), Sum> = BTreeMap::new();
    for pair in &mesh.face_pairs {
        let quad: [[f64; 3]; 4] = std::array::from_fn(|k| mesh.nodes[pair.nodes_a[k] as usize]);
        let area = quad4::area(&quad);
        let n = quad4::normal_scaled(&quad, [0.0, 0.0]);
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            .sqrt()
            .max(f64::MIN_POSITIVE);
        for k in 0..4 {
            let (a, b) = (pair.nodes_a[k], pair.nodes_b[k]);
            if a == b {
                continue;
            }
            let e = acc.entry((a, b)).or_insert(Sum {
                joint: pair.joint,
                zone: pair.zone,
                normal: [0.0; 3],
                area: 0.0,
            });
            for (s, nd) in e.normal.iter_mut().zip(n) {
                *s += 0.25 * area * nd / norm;
            }
            e.area += 0.25 * area;
        }
    }
    acc.into_iter()
        .map(|((a, b), sum)| {
            Ok(JointPoint {
                joint: sum.joint,
                zone: sum.zone,
                a,
                b,
                frame: LocalFrame::from_normal(sum.normal)?,
                area: sum.area,
            })
        })
        .collect()
}
