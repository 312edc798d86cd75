//! What a mechanical model is made of and a run never changes — the
//! element tables, the materials, the mesh's connectivity, the joint
//! points, the supports, the ordering plan and the condensed rock — and
//! what is computed from them alone: a live set's system and a step's K̃.
//!
//! It is shared ([`Arc`]) with the thread that factorises the next step
//! ahead ([`super::ahead`]), which analyses the next live set there when
//! the next step pours lifts, so that the step's own thread does not.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

use crate::fem::elasticity::{self, PackedSym24, SolidGauss};
use crate::fem::hex8_modes::{self, Modes};
use crate::fem::SparseSym;
use crate::material::creep::{self, StepCoefficients};
use crate::material::CreepLaw;
use crate::mesh::{Mesh, Part, SurfaceKind};
use crate::scene::{OrderingKind, SolidElement};

use super::ahead::Assembled;
use super::contact_step::JointSolveSettings;
use super::error::MechError;
use super::grout_stops::{inside_grout_stops, StopSample};
use super::joints::{build_points, JointPoint};
use super::layer_merging::LayerMerge;
use super::live::{
    ConstructionOrdering, ElementSet, LiveElement, LiveError, LiveSystem, OrderingPlan,
};
use super::rock_condensation::{CondensedRock, RockElements};
use super::rock_ties::Ties;
use super::settings::{JointMechanics, MechanicsSettings};

/// The unchanging parts of a mechanical model: what the scene's settings,
/// the mesh and the supports make, before any pour. Every run of one scene
/// and mesh can share it ([`super::MechanicsModel::on_frame`]): the
/// planner's re-simulations start on the baseline's frame instead of
/// making their own (the construction ordering's METIS call and the rock
/// condensation: 0.46–0.69 s of each re-simulation on the demo).
pub struct Frame {
    pub(super) settings: MechanicsSettings,
    pub(super) joint_settings: JointSolveSettings,
    pub(super) tables: ElementTables,
    /// the law of an element that does not creep (rock, or no `creep` effect)
    pub(super) no_creep: CreepLaw,
    pub(super) elements: Vec<[u32; 8]>,
    pub(super) n_nodes: usize,
    /// node coordinates (those the ties straighten, on their chords)
    pub(super) node_xyz: Vec<[f64; 3]>,
    /// the thermal unknown of each node
    pub(super) thermal_dof: Vec<u32>,
    /// the elements of each lift (block, lift)
    pub(super) lift_elems: BTreeMap<(u32, u32), Vec<u32>>,
    /// the element faces the reservoir wets (element, face)
    pub(super) wet_faces: Vec<(u32, u8)>,
    /// contact points of the joints (the `joints` effect)
    pub(super) points: Vec<JointPoint>,
    /// joint point of each side-a node
    pub(super) point_of_a: HashMap<u32, u32>,
    /// per zone, where its aperture is sampled inside the grout stops
    pub(super) zone_stop_samples: HashMap<(u32, u32), Vec<StopSample>>,
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

/// What making a [`Frame`] cost; the model that makes one counts it.
pub(super) struct FrameCosts {
    pub(super) metis_calls: usize,
    pub(super) seconds_ordering: f64,
    pub(super) seconds_condensation: f64,
}

impl Frame {
    /// The frame of `mesh` under `settings` with the dofs `supported` held.
    pub(super) fn build(
        mesh: &Mesh,
        settings: &MechanicsSettings,
        supported: Vec<bool>,
    ) -> Result<(Frame, FrameCosts), MechError> {
        let ties = Ties::build(
            &mesh.elements,
            &mesh.parts,
            &mesh.nodes,
            &supported,
            settings.rock_coarsening,
        );
        let merge = LayerMerge::build(mesh, &supported, settings.layer_merging_age_days);
        // the mechanics' rock is the tied one and its concrete the one
        // merging ties, the nodes tied on their chords
        let straightened;
        let mesh = if ties.count() > 0 || !merge.is_empty() {
            let mut m = mesh.clone();
            ties.straighten(&mut m.nodes);
            merge.straighten(&mut m.nodes);
            straightened = m;
            &straightened
        } else {
            mesh
        };
        let tables = ElementTables::new(mesh, settings)?;
        let points = if settings.joints {
            build_points(mesh).map_err(|source| MechError::Contact { day: 0.0, source })?
        } else {
            Vec::new()
        };
        let mut costs = FrameCosts {
            metis_calls: 0,
            seconds_ordering: 0.0,
            seconds_condensation: 0.0,
        };
        let ordering = ordering_plan(
            mesh, settings, &points, &supported, &ties, &merge, &mut costs,
        )?;
        let rock = condensed_rock(
            mesh, settings, &tables, &ordering, &points, &supported, &ties,
        )?;
        if let Some((_, seconds)) = &rock {
            costs.seconds_condensation = *seconds;
        }
        let frame = Frame {
            settings: settings.clone(),
            joint_settings: joint_solve_settings(mesh, &settings.joint),
            tables,
            no_creep: CreepLaw { terms: Vec::new() },
            elements: mesh.elements.clone(),
            n_nodes: mesh.nodes.len(),
            node_xyz: mesh.nodes.clone(),
            thermal_dof: mesh.thermal_dof.clone(),
            lift_elems: mesh.lift_elements(),
            wet_faces: mesh
                .surfaces
                .iter()
                .filter(|s| s.kind == SurfaceKind::Wet)
                .map(|s| (s.elem, s.face))
                .collect(),
            point_of_a: points
                .iter()
                .enumerate()
                .map(|(i, p)| (p.a, i as u32))
                .collect(),
            zone_stop_samples: inside_grout_stops(mesh, &points, settings.joint.grout_stop_inset_m),
            points,
            supported,
            ties,
            merge,
            ordering,
            rock: rock.map(|(r, _)| Arc::new(r)),
        };
        Ok((frame, costs))
    }

    /// Marks the elements of `lifts` (block, lift) live in `live` and born
    /// on `day` in `birth`; whether the lifts have any element.
    pub(super) fn pour(
        &self,
        lifts: &[(u32, u32)],
        day: f64,
        live: &mut [bool],
        birth: &mut [f64],
    ) -> bool {
        let mut any = false;
        for &e in lifts
            .iter()
            .flat_map(|key| self.lift_elems.get(key).into_iter().flatten())
        {
            live[e as usize] = true;
            birth[e as usize] = day;
            any = true;
        }
        any
    }

    /// Creep terms per Gauss point of a concrete element (0 without the
    /// `creep` effect).
    pub(super) fn creep_terms(&self) -> usize {
        self.settings
            .concrete
            .creep
            .as_ref()
            .map_or(0, |l| l.n_terms())
    }

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
            None => a.add_packed_scaled(slot, modulus, &self.tables.k_unit[el.elem as usize].0),
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
            let concrete = &self.settings.concrete;
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

/// How the live sets of `mesh` are ordered (`solver.ordering`); the
/// construction ordering's METIS call is counted in `costs`.
fn ordering_plan(
    mesh: &Mesh,
    settings: &MechanicsSettings,
    points: &[JointPoint],
    supported: &[bool],
    ties: &Ties,
    merge: &LayerMerge,
    costs: &mut FrameCosts,
) -> Result<OrderingPlan, MechError> {
    Ok(match settings.ordering {
        OrderingKind::Amd => OrderingPlan::Amd,
        OrderingKind::MetisLiveSet => OrderingPlan::MetisLiveSet,
        OrderingKind::Metis => {
            let c = ConstructionOrdering::new(
                &mesh.elements,
                points,
                supported,
                mesh.nodes.len(),
                ties,
                merge,
            )
            .map_err(|source| MechError::Live { day: 0.0, source })?;
            costs.metis_calls += c.metis_calls;
            costs.seconds_ordering += c.seconds;
            OrderingPlan::Construction(Arc::new(c))
        }
    })
}

/// The rock to condense once per run and the seconds it took: with
/// `solver.condense_rock`, the construction ordering, no tied rock and some
/// column frozen ([`super::rock_condensation`]).
fn condensed_rock(
    mesh: &Mesh,
    settings: &MechanicsSettings,
    tables: &ElementTables,
    ordering: &OrderingPlan,
    points: &[JointPoint],
    supported: &[bool],
    ties: &Ties,
) -> Result<Option<(CondensedRock, f64)>, MechError> {
    let OrderingPlan::Construction(c) = ordering else {
        return Ok(None);
    };
    if !settings.condense_rock || ties.count() > 0 {
        return Ok(None);
    }
    let t = Instant::now();
    let rock: Vec<bool> = tables.concrete.iter().map(|&c| !c).collect();
    let mut rock_only = vec![true; mesh.nodes.len()];
    let mut used = vec![false; mesh.nodes.len()];
    for (e, conn) in mesh.elements.iter().enumerate() {
        for &v in conn {
            used[v as usize] = true;
            rock_only[v as usize] &= rock[e];
        }
    }
    let frozen = c
        .frozen(&mesh.elements, points, &|v| used[v] && rock_only[v])
        .map_err(|source| MechError::Live { day: 0.0, source })?;
    let elements = RockElements {
        conn: &mesh.elements,
        rock: &rock,
        k_unit: &tables.k_unit,
        modulus: tables.rock_modulus,
        supported,
    };
    let condensed = CondensedRock::new(&elements, &frozen).map_err(MechError::Condensation)?;
    Ok(condensed.map(|r| (r, t.elapsed().as_secs_f64())))
}

/// The joint solver's settings for `mesh`. Gaps are compared to 1e-10 of
/// the model's size, forces to 1e-9 of the step's largest force: the same
/// decisions in m/N and mm/MPa units.
fn joint_solve_settings(mesh: &Mesh, joint: &JointMechanics) -> JointSolveSettings {
    let (lo, hi) = mesh
        .nodes
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        });
    let size = (0..3)
        .map(|k| (hi[k] - lo[k]).max(0.0).powi(2))
        .sum::<f64>()
        .sqrt();
    JointSolveSettings {
        method: joint.solver,
        mu_static: joint.mu_static,
        mu_kinetic: joint.mu_kinetic,
        max_iterations: joint.max_iterations,
        gap_tolerance: 1e-10 * size,
        force_tolerance: 1e-9,
        bond_strength: joint.bond_strength_pa,
        capacitance: joint.capacitance,
    }
}

/// Per-element constants of the mechanical problem, computed once.
pub(super) struct ElementTables {
    /// Gauss points of each element
    pub(super) gauss: Vec<[SolidGauss; 8]>,
    /// stiffness at unit modulus (the modulus ages, ν does not); with the
    /// incompatible modes, the condensed one
    pub(super) k_unit: Vec<PackedSym24>,
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
    /// the rock's modulus (0 without rock elements) \[Pa\]
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
                t.k_unit.push(PackedSym24::from_upper(&k));
                t.modes.push(m);
            } else {
                t.k_unit
                    .push(PackedSym24::from_upper(&elasticity::stiffness(&g, &q)));
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
