//! What a mechanical model is made of and a run never changes — the
//! element tables, the materials, the mesh's connectivity, the joint
//! points, the supports, the ordering plan and the condensed rock — and
//! what is computed from them alone: a live set's system and a step's K̃.
//!
//! It is shared ([`Arc`]) with the thread that factorises the next step
//! ahead ([`super::ahead`]), which analyses the next live set there when
//! the next step pours lifts, so that the step's own thread does not.

use std::sync::Arc;

use crate::fem::elasticity::{self, Mat24, SolidGauss};
use crate::fem::hex8_modes::{self, Modes};
use crate::fem::SparseSym;
use crate::material::creep::{self, StepCoefficients};
use crate::material::CreepLaw;
use crate::mesh::{Mesh, Part};
use crate::scene::SolidElement;

use super::ahead::Assembled;
use super::error::MechError;
use super::joints::JointPoint;
use super::layer_merging::LayerMerge;
use super::live::{ElementSet, LiveElement, LiveError, LiveSystem, OrderingPlan};
use super::rock_condensation::CondensedRock;
use super::rock_ties::Ties;
use super::settings::{ConcreteMechanics, MechanicsSettings};

/// The unchanging parts of a mechanical model.
pub(super) struct Frame {
    pub(super) tables: ElementTables,
    /// the concrete's laws (ageing modulus, creep)
    pub(super) concrete: ConcreteMechanics,
    /// the law of an element that does not creep (rock, or no `creep` effect)
    pub(super) no_creep: CreepLaw,
    pub(super) elements: Vec<[u32; 8]>,
    pub(super) n_nodes: usize,
    /// contact points of the joints (the `joints` effect)
    pub(super) points: Vec<JointPoint>,
    /// per global dof: held by a support
    pub(super) supported: Vec<bool>,
    /// the rock nodes tied to their grid lines (`solver.rock_coarsening`)
    pub(super) ties: Ties,
    /// the concrete ties of layer merging (`solver.layer_merging_age_days`)
    pub(super) merge: LayerMerge,
    /// how each live set's elimination order is chosen
    pub(super) ordering: OrderingPlan,
    /// the rock condensed once per run (`solver.condense_rock`)
    pub(super) rock: Option<Arc<CondensedRock>>,
}

impl Frame {
    /// Numbers and analyses the live system of the elements `live` (the
    /// joint points `pair_live` paired, the nodes `merged` tied by layer
    /// merging), with its rock matrix.
    pub(super) fn live_system(
        &self,
        live: &[bool],
        pair_live: &[bool],
        merged: &[u32],
    ) -> Result<LiveSystem, LiveError> {
        let with_merged;
        let ties = if merged.is_empty() {
            &self.ties
        } else {
            let extra = merged
                .iter()
                .filter_map(|&v| self.merge.tie_of(v).map(|t| (v, t)));
            with_merged = self.ties.with(extra, self.n_nodes);
            &with_merged
        };
        let elements = ElementSet {
            conn: &self.elements,
            live,
            k_unit: &self.tables.k_unit,
            ties,
            rock: self.rock.as_ref(),
        };
        let mut sys = LiveSystem::build(
            elements,
            &self.points,
            pair_live,
            &self.supported,
            self.n_nodes,
            &self.ordering,
        )?;
        sys.rock_matrix = self.rock_matrix(&sys);
        Ok(sys)
    }

    /// The part of `sys`'s matrix no step changes: its rock elements (not
    /// condensed) at the rock's modulus (the e_eff of a step's
    /// coefficients: the rock neither ages nor creeps), and −C of the
    /// condensed rock, in one slot per block after the elements. None
    /// without rock.
    pub(super) fn rock_matrix(&self, sys: &LiveSystem) -> Option<SparseSym> {
        let rock = |el: &&LiveElement| !self.tables.concrete[el.elem as usize];
        if sys.rock.is_none() && !sys.elements.iter().any(|el| rock(&el)) {
            return None;
        }
        let mut a = SparseSym::new(sys.pattern.clone());
        for (slot, el) in sys.elements.iter().enumerate() {
            if rock(&el) && !el.condensed {
                self.add_stiffness(&mut a, slot, el, self.tables.rock_modulus);
            }
        }
        for (t, block) in sys.rock.iter().flat_map(|r| r.blocks.iter()).enumerate() {
            a.add_element(sys.elements.len() + t, &block.minus_c);
        }
        Some(a)
    }

    /// Adds `modulus` times the unit-modulus stiffness of the live element
    /// `el` (slot `slot`) to `a`.
    pub(super) fn add_stiffness(
        &self,
        a: &mut SparseSym,
        slot: usize,
        el: &LiveElement,
        modulus: f64,
    ) {
        match &el.k_unit {
            Some(k) => a.add_element_scaled(slot, modulus, k),
            None => a.add_element_scaled(slot, modulus, &self.tables.k_unit[el.elem as usize]),
        }
    }

    /// The step coefficients of element `e`, born on `birth`, over (t0, t1).
    pub(super) fn coefficients(
        &self,
        e: usize,
        birth: f64,
        t0: f64,
        t1: f64,
    ) -> Result<StepCoefficients, MechError> {
        let (age0, age1) = ((t0 - birth).max(0.0), t1 - birth);
        let res = if self.tables.concrete[e] {
            let concrete = &self.concrete;
            creep::coefficients(
                &concrete.modulus,
                concrete.creep.as_ref().unwrap_or(&self.no_creep),
                age0,
                age1,
            )
        } else {
            creep::coefficients(&self.tables.rock_modulus, &self.no_creep, age0, age1)
        };
        res.map_err(|source| MechError::Age {
            element: e,
            day: t1,
            source,
        })
    }

    /// The stiffness K̃ of the elements of `sys` born on `birth` over
    /// (t0, t1), at their mid-step ages, with their coefficients (what
    /// `MechanicsModel::assemble` makes when they are the live ones).
    pub(super) fn stiffness(
        &self,
        sys: &LiveSystem,
        birth: &[f64],
        t0: f64,
        t1: f64,
    ) -> Result<Assembled, MechError> {
        let mut a = match &sys.rock_matrix {
            Some(rock) => rock.clone(),
            None => SparseSym::new(sys.pattern.clone()),
        };
        let rock_made = sys.rock_matrix.is_some();
        let mut coeffs = Vec::with_capacity(sys.elements.len());
        let mut born = Vec::with_capacity(sys.elements.len());
        for (slot, el) in sys.elements.iter().enumerate() {
            let e = el.elem as usize;
            let c = self.coefficients(e, birth[e], t0, t1)?;
            let constant = el.condensed || (rock_made && !self.tables.concrete[e]);
            if !constant {
                self.add_stiffness(&mut a, slot, el, c.e_eff);
            }
            coeffs.push(c);
            born.push(birth[e]);
        }
        Ok(Assembled {
            stiffness: a,
            coeffs,
            born,
        })
    }
}

/// Per-element constants of the mechanical problem, computed once.
pub(super) struct ElementTables {
    /// Gauss points of each element
    pub(super) gauss: Vec<[SolidGauss; 8]>,
    /// stiffness at unit modulus (the modulus ages, ν does not); with the
    /// incompatible modes, the condensed one
    pub(super) k_unit: Vec<Mat24>,
    /// the incompatible modes of each element (`solver.element =
    /// "hex8_incompatible"`; empty with the plain hex8)
    pub(super) modes: Vec<Modes>,
    /// Poisson's ratio
    pub(super) nu: Vec<f64>,
    /// thermal expansion [1/°C], zero without the `thermal_strain` effect
    pub(super) alpha: Vec<f64>,
    /// density [kg/m³]
    pub(super) density: Vec<f64>,
    /// concrete (ageing, creeping) or rock (elastic)
    pub(super) concrete: Vec<bool>,
    /// the rock's modulus (0 without rock elements) [Pa]
    pub(super) rock_modulus: f64,
}

impl ElementTables {
    pub(super) fn new(
        mesh: &Mesh,
        settings: &MechanicsSettings,
    ) -> Result<ElementTables, MechError> {
        let c = &settings.concrete;
        let n_el = mesh.elements.len();
        let mut t = ElementTables {
            gauss: Vec::with_capacity(n_el),
            k_unit: Vec::with_capacity(n_el),
            modes: vec![],
            nu: vec![],
            alpha: vec![],
            density: vec![],
            concrete: vec![],
            rock_modulus: 0.0,
        };
        for (e, part) in mesh.parts.iter().enumerate() {
            let coords = mesh.element_coords(e);
            let g = elasticity::gauss_points(&coords)
                .map_err(|source| MechError::Element { element: e, source })?;
            let (n, a, rho, is_c) = match part {
                Part::Concrete { .. } => (c.poisson, c.expansion_per_c, c.density_kg_m3, true),
                Part::Rock => {
                    let r = settings.rock.as_ref().ok_or(MechError::NoRock)?;
                    t.rock_modulus = r.modulus_pa;
                    (r.poisson, r.expansion_per_c, r.density_kg_m3, false)
                }
            };
            let q = elasticity::poisson_matrix(n);
            if settings.element == SolidElement::Hex8Incompatible {
                let (k, m) = hex8_modes::modes(&coords, &g, &q)
                    .map_err(|source| MechError::Element { element: e, source })?;
                t.k_unit.push(k);
                t.modes.push(m);
            } else {
                t.k_unit.push(elasticity::stiffness(&g, &q));
            }
            t.gauss.push(g);
            t.nu.push(n);
            t.alpha.push(if settings.thermal_strain { a } else { 0.0 });
            t.density.push(rho);
            t.concrete.push(is_c);
        }
        Ok(t)
    }
}
