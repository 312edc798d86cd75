//! The mechanical model of the live elements and its incremental step.

use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::elasticity::{self, Mat24, SolidGauss};
use crate::fem::hex8::FACES;
use crate::fem::{
    nested_dissection, CholeskySolver, ElementError, Ordering, Pattern, SolveError, SparseSym,
};
use crate::joint::{ContactProblem, ContactSettings, FrictionModel};
use crate::material::creep::{self, CreepState, StepCoefficients};
use crate::material::{AgeStepError, AutogenousLaw, CreepLaw, ModulusLaw, Poisson};
use crate::mesh::{Mesh, Part, SurfaceKind};
use crate::scene::{Effect, Scene};

use super::joints::{build_points, JointPoint, JointPointState, PointState};

/// Gravity [m/s²].
pub const GRAVITY: f64 = 9.81;
/// Water density [kg/m³].
pub const WATER_DENSITY: f64 = 1000.0;
/// Relative residual above which a mechanical solve is rejected.
const RESIDUAL_TOLERANCE: f64 = 1e-8;

#[derive(Debug, thiserror::Error)]
pub enum MechError {
    #[error("mechanical solve on day {day:.3}: {source}")]
    Solve { day: f64, source: SolveError },
    #[error("mechanical solve on day {day:.3}: relative residual {residual:.3e} exceeds {RESIDUAL_TOLERANCE:.0e}")]
    Residual { day: f64, residual: f64 },
    #[error("element {element}: {source}")]
    Element {
        element: usize,
        source: ElementError,
    },
    #[error("element {element} on day {day:.3}: {source}")]
    Age {
        element: usize,
        day: f64,
        source: AgeStepError,
    },
    #[error("the scene has mechanical effects but no {0}")]
    Missing(&'static str),
    #[error("joint contact on day {day:.3}: {source}")]
    Contact {
        day: f64,
        source: crate::joint::ContactError,
    },
}

/// Prescribed zero displacement increments: (node, component 0..3).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Supports {
    pub fixed: Vec<(u32, u8)>,
}

impl Supports {
    /// All three components of every node on the far boundary of the model
    /// (rock bottom and sides; the base of a mesh without rock).
    pub fn far_boundary(mesh: &Mesh) -> Supports {
        let mut fixed = Vec::new();
        for s in mesh.surfaces.iter().filter(|s| s.kind == SurfaceKind::Far) {
            for &k in &FACES[s.face as usize] {
                let node = mesh.elements[s.elem as usize][k];
                for c in 0..3 {
                    fixed.push((node, c));
                }
            }
        }
        fixed.sort_unstable();
        fixed.dedup();
        Supports { fixed }
    }
}

/// Counters for the benchmark.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MechStats {
    pub steps: usize,
    pub symbolic: usize,
    pub numeric: usize,
    pub max_dofs: usize,
    pub seconds_symbolic: f64,
    pub seconds_numeric: f64,
    pub seconds_solve: f64,
    pub seconds_assembly: f64,
}

/// Checkpointable mechanical state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MechState {
    /// displacement accumulated since each node's birth, 3 per node [m]
    pub u: Vec<f64>,
    pub live: Vec<bool>,
    /// per element: day it was born (NaN before)
    pub birth_day: Vec<f64>,
    /// per element and Gauss point [Pa]
    pub stress: Vec<[[f64; 6]; 8]>,
    /// per element × 8 Gauss points when creep is on
    pub creep: Vec<CreepState>,
    /// external load accumulated so far, per dof [N]
    pub f_ext: Vec<f64>,
    /// water load applied so far, per dof [N]
    pub water_load: Vec<f64>,
    pub weight_applied: Vec<bool>,
    /// one per joint contact point (empty without the `joints` effect)
    pub joints: Vec<JointPointState>,
    /// nodal forces of the joint contacts, per dof [N] (total, not incremental)
    pub f_contact: Vec<f64>,
}

struct LiveMech {
    dofs: Vec<u32>,
    index_of: Vec<u32>,
    elems: Vec<u32>,
    pattern: Arc<Pattern>,
    solver: CholeskySolver,
    fixed: Vec<bool>,
}

const NONE: u32 = u32::MAX;

/// The staged mechanical model.
pub struct MechanicsModel {
    gauss: Vec<[SolidGauss; 8]>,
    k_unit: Vec<Mat24>,
    nu: Vec<f64>,
    alpha: Vec<f64>,
    density: Vec<f64>,
    concrete: Vec<bool>,
    modulus: ModulusLaw,
    rock_modulus: f64,
    creep_law: Option<CreepLaw>,
    no_creep: CreepLaw,
    autogenous: Option<AutogenousLaw>,
    thermal_strain: bool,
    self_weight: bool,
    reservoir_load: bool,
    node_xyz: Vec<[f64; 3]>,
    elements: Vec<[u32; 8]>,
    thermal_dof: Vec<u32>,
    lift_elems: std::collections::HashMap<(u32, u32), Vec<u32>>,
    supported: Vec<bool>,
    wet_faces: Vec<(u32, u8)>,
    sys: Option<LiveMech>,
    dirty: bool,
    /// contact points of the joints (the `joints` effect)
    pub points: Vec<JointPoint>,
    friction: FrictionModel,
    initial_gap: f64,
    pub state: MechState,
    pub stats: MechStats,
}

impl MechanicsModel {
    /// Builds the model; rock elements are born (stress-free) at day 0.
    pub fn new(
        mesh: &Mesh,
        scene: &Scene,
        supports: &Supports,
    ) -> Result<MechanicsModel, MechError> {
        let c = &scene.concrete;
        let modulus = c.modulus.ok_or(MechError::Missing("concrete.modulus"))?;
        let nu_c = c.poisson.ok_or(MechError::Missing("concrete.poisson"))?;
        let n_el = mesh.elements.len();
        let (mut gauss, mut k_unit) = (Vec::with_capacity(n_el), Vec::with_capacity(n_el));
        let (mut nu, mut alpha, mut density, mut concrete) = (vec![], vec![], vec![], vec![]);
        let mut rock_modulus = 0.0;
        for (e, part) in mesh.parts.iter().enumerate() {
            let coords = mesh.element_coords(e);
            let g = elasticity::gauss_points(&coords)
                .map_err(|source| MechError::Element { element: e, source })?;
            let (n, a, rho, is_c) = match part {
                Part::Concrete { .. } => (
                    nu_c,
                    c.expansion_per_c.unwrap_or(0.0),
                    c.density_kg_m3,
                    true,
                ),
                Part::Rock => {
                    let r = scene
                        .rock
                        .as_ref()
                        .ok_or(MechError::Missing("[rock] table"))?;
                    rock_modulus = r.modulus_pa.ok_or(MechError::Missing("rock.modulus_pa"))?;
                    (
                        r.poisson.unwrap_or(0.25),
                        r.expansion_per_c.unwrap_or(0.0),
                        r.density_kg_m3,
                        false,
                    )
                }
            };
            k_unit.push(elasticity::stiffness(&g, &elasticity::isotropic_d(1.0, n)));
            gauss.push(g);
            nu.push(n);
            alpha.push(if scene.has(Effect::ThermalStrain) {
                a
            } else {
                0.0
            });
            density.push(rho);
            concrete.push(is_c);
        }
        let mut supported = vec![false; 3 * mesh.nodes.len()];
        for &(node, comp) in &supports.fixed {
            supported[3 * node as usize + comp as usize] = true;
        }
        let mut lift_elems: std::collections::HashMap<(u32, u32), Vec<u32>> = Default::default();
        for (e, part) in mesh.parts.iter().enumerate() {
            if let Part::Concrete { block, lift } = part {
                lift_elems
                    .entry((*block, *lift))
                    .or_default()
                    .push(e as u32);
            }
        }
        let creep_law = if scene.has(Effect::Creep) {
            c.creep.clone()
        } else {
            None
        };
        let points = if scene.has(Effect::Joints) {
            build_points(mesh).map_err(|source| MechError::Contact { day: 0.0, source })?
        } else {
            Vec::new()
        };
        let j = &scene.joints;
        let friction = if j.mu_static == 0.0 {
            FrictionModel::Frictionless
        } else {
            FrictionModel::Coulomb {
                mu_s: j.mu_static,
                mu_k: j.mu_kinetic,
            }
        };
        let n_creep = creep_law.as_ref().map_or(0, |l| l.n_terms());
        let mut model = MechanicsModel {
            gauss,
            k_unit,
            nu,
            alpha,
            density,
            concrete,
            modulus,
            rock_modulus,
            creep_law,
            no_creep: CreepLaw { terms: Vec::new() },
            autogenous: if scene.has(Effect::Autogenous) {
                c.autogenous
            } else {
                None
            },
            thermal_strain: scene.has(Effect::ThermalStrain),
            self_weight: scene.has(Effect::SelfWeight),
            reservoir_load: scene.has(Effect::ReservoirLoad),
            node_xyz: mesh.nodes.clone(),
            elements: mesh.elements.clone(),
            thermal_dof: mesh.thermal_dof.clone(),
            lift_elems,
            supported,
            wet_faces: mesh
                .surfaces
                .iter()
                .filter(|s| s.kind == SurfaceKind::Wet)
                .map(|s| (s.elem, s.face))
                .collect(),
            sys: None,
            dirty: true,
            friction,
            initial_gap: j.initial_gap_m,
            state: MechState {
                joints: vec![
                    JointPointState {
                        paired: false,
                        gap: 0.0,
                        force: [0.0; 3],
                        state: PointState::Open
                    };
                    points.len()
                ],
                f_contact: vec![0.0; 3 * mesh.nodes.len()],
                u: vec![0.0; 3 * mesh.nodes.len()],
                live: vec![false; n_el],
                birth_day: vec![f64::NAN; n_el],
                stress: vec![[[0.0; 6]; 8]; n_el],
                creep: if n_creep > 0 {
                    vec![CreepState::new(n_creep); 8 * n_el]
                } else {
                    Vec::new()
                },
                f_ext: vec![0.0; 3 * mesh.nodes.len()],
                water_load: vec![0.0; 3 * mesh.nodes.len()],
                weight_applied: vec![false; n_el],
            },
            stats: MechStats::default(),
            points,
        };
        for e in 0..n_el {
            if !model.concrete[e] {
                model.state.live[e] = true;
                model.state.birth_day[e] = 0.0;
                // The foundation's own weight is in equilibrium with the ground
                // before construction: it does not strain the rock.
                model.state.weight_applied[e] = true;
            }
        }
        Ok(model)
    }

    /// Pours lift `lift` of `block` on `day`: its elements are born stress-free.
    pub fn pour(&mut self, block: u32, lift: u32, day: f64) {
        if let Some(elems) = self.lift_elems.get(&(block, lift)) {
            for &e in elems {
                self.state.live[e as usize] = true;
                self.state.birth_day[e as usize] = day;
            }
            self.dirty = true;
        }
    }

    fn rebuild(&mut self) -> Result<(), SolveError> {
        let t = Instant::now();
        let n_nodes = self.node_xyz.len();
        let mut index_of = vec![NONE; 3 * n_nodes];
        let mut dofs = Vec::new();
        let mut elems = Vec::new();
        let mut local = Vec::new();
        for e in 0..self.elements.len() {
            if !self.state.live[e] {
                continue;
            }
            let gd = elasticity::element_dofs(&self.elements[e]);
            let mut ld = [0u32; 24];
            for (k, &d) in gd.iter().enumerate() {
                if index_of[d as usize] == NONE {
                    index_of[d as usize] = dofs.len() as u32;
                    dofs.push(d);
                }
                ld[k] = index_of[d as usize];
            }
            elems.push(e as u32);
            local.push(ld);
        }
        let n = dofs.len();
        let pattern = Arc::new(Pattern::new(n, &local));
        let xyz: Vec<[f64; 3]> = dofs
            .iter()
            .map(|&d| self.node_xyz[d as usize / 3])
            .collect();
        let ordering = Ordering::Custom(nested_dissection(&pattern, &xyz, 64));
        let par = if n < 30_000 {
            faer::Par::Seq
        } else {
            faer::Par::rayon(0)
        };
        let solver = CholeskySolver::with_options(pattern.clone(), &ordering, par)?;
        let fixed = dofs.iter().map(|&d| self.supported[d as usize]).collect();
        self.stats.symbolic += 1;
        self.stats.max_dofs = self.stats.max_dofs.max(n);
        self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
        self.sys = Some(LiveMech {
            dofs,
            index_of,
            elems,
            pattern,
            solver,
            fixed,
        });
        self.dirty = false;
        Ok(())
    }

    fn coefficients(&self, e: usize, t0: f64, t1: f64) -> Result<StepCoefficients, MechError> {
        let birth = self.state.birth_day[e];
        let (age0, age1) = ((t0 - birth).max(0.0), t1 - birth);
        let res = if self.concrete[e] {
            creep::coefficients(
                &self.modulus,
                self.creep_law.as_ref().unwrap_or(&self.no_creep),
                age0,
                age1,
            )
        } else {
            creep::coefficients(&self.rock_modulus, &self.no_creep, age0, age1)
        };
        res.map_err(|source| MechError::Age {
            element: e,
            day: t1,
            source,
        })
    }

    /// Temperature at each Gauss point of element `e` from thermal-dof temperatures.
    fn gauss_temperatures(&self, e: usize, temps: &[f64]) -> [f64; 8] {
        let conn = &self.elements[e];
        std::array::from_fn(|g| {
            let n = crate::fem::hex8::shape(self.gauss[e][g].xi);
            (0..8)
                .map(|k| n[k] * temps[self.thermal_dof[conn[k] as usize] as usize])
                .sum()
        })
    }

    /// Hydrostatic load of the water at `level` on the live wet faces, per dof.
    fn water_load(&self, level: Option<f64>) -> Result<Vec<f64>, MechError> {
        let mut f = vec![0.0; self.state.u.len()];
        let Some(level) = level.filter(|_| self.reservoir_load) else {
            return Ok(f);
        };
        for &(e, face) in &self.wet_faces {
            if !self.state.live[e as usize] {
                continue;
            }
            let ids = FACES[face as usize];
            let fc: [[f64; 3]; 4] =
                std::array::from_fn(|k| self.node_xyz[self.elements[e as usize][ids[k]] as usize]);
            if fc.iter().all(|p| p[2] >= level) {
                continue;
            }
            let load = elasticity::face_pressure(&fc, |x| {
                WATER_DENSITY * GRAVITY * (level - x[2]).max(0.0)
            })
            .map_err(|source| MechError::Element {
                element: e as usize,
                source,
            })?;
            for k in 0..4 {
                let node = self.elements[e as usize][ids[k]] as usize;
                for c in 0..3 {
                    f[3 * node + c] += load[3 * k + c];
                }
            }
        }
        Ok(f)
    }

    /// Advances from t0 to t1. `temps` are the thermal-dof temperatures at t0
    /// (after the pours of t0) and at t1, when a thermal field exists;
    /// `water_level` is the reservoir level at t1.
    pub fn step(
        &mut self,
        t0: f64,
        t1: f64,
        temps: Option<(&[f64], &[f64])>,
        water_level: Option<f64>,
    ) -> Result<(), MechError> {
        if self.dirty {
            self.rebuild()
                .map_err(|source| MechError::Solve { day: t1, source })?;
        }
        let t_asm = Instant::now();
        let sys = self.sys.as_ref().expect("built");
        let n = sys.dofs.len();
        let mut a = SparseSym::new(sys.pattern.clone());
        let mut b = vec![0.0; n];
        let mut coeffs = Vec::with_capacity(sys.elems.len());
        let mut pseudo: Vec<[[f64; 6]; 8]> = Vec::with_capacity(sys.elems.len());
        for (slot, &e) in sys.elems.iter().enumerate() {
            let e = e as usize;
            let c = self.coefficients(e, t0, t1)?;
            a.add_element_scaled(slot, c.e_eff, &self.k_unit[e]);
            // Strains the step imposes at constant stress: creep, thermal, autogenous.
            let mut eps = [[0.0; 6]; 8];
            if !self.state.creep.is_empty() && self.concrete[e] {
                for (g, eg) in eps.iter_mut().enumerate() {
                    *eg = creep::eta(&self.state.creep[8 * e + g], &c);
                }
            }
            let mut volumetric = [0.0; 8];
            if let (true, Some((before, after))) =
                (self.thermal_strain && self.alpha[e] != 0.0, temps)
            {
                let (t_a, t_b) = (
                    self.gauss_temperatures(e, before),
                    self.gauss_temperatures(e, after),
                );
                for g in 0..8 {
                    volumetric[g] += self.alpha[e] * (t_b[g] - t_a[g]);
                }
            }
            if let (Some(law), true) = (&self.autogenous, self.concrete[e]) {
                let dg = law.increment(c.age0, c.age1);
                volumetric.iter_mut().for_each(|v| *v += dg);
            }
            for g in 0..8 {
                for k in 0..3 {
                    eps[g][k] += volumetric[g];
                }
            }
            let d = elasticity::isotropic_d(c.e_eff, self.nu[e]);
            let load = elasticity::initial_strain_load(&self.gauss[e], &d, &eps);
            let gd = elasticity::element_dofs(&self.elements[e]);
            for k in 0..24 {
                b[sys.index_of[gd[k] as usize] as usize] += load[k];
            }
            coeffs.push(c);
            pseudo.push(eps);
        }
        // External load increments: self-weight of the newborn, water.
        let mut df_ext = vec![0.0; self.state.u.len()];
        if self.self_weight {
            for &e in &sys.elems {
                let e = e as usize;
                if !self.state.weight_applied[e] {
                    let w = elasticity::body_force_at(
                        &self.gauss[e],
                        [0.0, 0.0, -self.density[e] * GRAVITY],
                    );
                    let gd = elasticity::element_dofs(&self.elements[e]);
                    for k in 0..24 {
                        df_ext[gd[k] as usize] += w[k];
                    }
                }
            }
        }
        let water = self.water_load(water_level)?;
        for i in 0..water.len() {
            df_ext[i] += water[i] - self.state.water_load[i];
        }
        for (i, &d) in sys.dofs.iter().enumerate() {
            b[i] += df_ext[d as usize];
        }
        a.apply_dirichlet(&sys.fixed);
        for i in 0..n {
            if sys.fixed[i] {
                b[i] = 0.0;
            }
        }
        self.stats.seconds_assembly += t_asm.elapsed().as_secs_f64();

        let sys = self.sys.as_mut().expect("built");
        let t_num = Instant::now();
        sys.solver
            .factorize(&a)
            .map_err(|source| MechError::Solve { day: t1, source })?;
        self.stats.numeric += 1;
        self.stats.seconds_numeric += t_num.elapsed().as_secs_f64();
        let t_solve = Instant::now();
        let mut x = b.clone();
        sys.solver
            .solve_in_place(&mut x)
            .map_err(|source| MechError::Solve { day: t1, source })?;
        self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
        let residual = crate::fem::relative_residual(&a, &x, &b);
        if !(residual <= RESIDUAL_TOLERANCE) {
            return Err(MechError::Residual { day: t1, residual });
        }
        if !self.points.is_empty() {
            x = self.solve_joints(&x, t1)?;
        }

        // Commit: displacements, stresses, creep states, loads.
        let sys = self.sys.as_ref().expect("built");
        let mut du = vec![0.0; self.state.u.len()];
        for (i, &d) in sys.dofs.iter().enumerate() {
            du[d as usize] = x[i];
            self.state.u[d as usize] += x[i];
        }
        for (slot, &e) in sys.elems.iter().enumerate() {
            let e = e as usize;
            let gd = elasticity::element_dofs(&self.elements[e]);
            let ue: [f64; 24] = std::array::from_fn(|k| du[gd[k] as usize]);
            let c = &coeffs[slot];
            let nu = Poisson(self.nu[e]);
            for g in 0..8 {
                let deps = elasticity::strain(&self.gauss[e][g], &ue);
                let mut net = [0.0; 6];
                for k in 0..6 {
                    net[k] = deps[k] - pseudo[slot][g][k];
                }
                let ds = nu.q_apply(&net).map(|v| c.e_eff * v);
                for k in 0..6 {
                    self.state.stress[e][g][k] += ds[k];
                }
                if !self.state.creep.is_empty() && self.concrete[e] {
                    creep::commit(&mut self.state.creep[8 * e + g], c, nu, &ds);
                }
            }
            if self.self_weight {
                self.state.weight_applied[e] = true;
            }
        }
        for i in 0..df_ext.len() {
            self.state.f_ext[i] += df_ext[i];
        }
        self.state.water_load = water;
        self.stats.steps += 1;
        Ok(())
    }

    /// Joint contact of the step: given the free increment `x0` (no change of
    /// contact forces), finds the total contact forces of the live points
    /// from the condensed problem u = b + W r (W = C A⁻¹ Cᵀ by multi-column
    /// solves on the step's factor, `joint::solve`), and returns
    /// Δu = x0 + A⁻¹Cᵀ(r − r_old).
    fn solve_joints(&mut self, x0: &[f64], day: f64) -> Result<Vec<f64>, MechError> {
        let sys = self.sys.as_ref().expect("built");
        let n = sys.dofs.len();
        let live: Vec<usize> = (0..self.points.len())
            .filter(|&p| {
                let (a, b) = (self.points[p].a as usize, self.points[p].b as usize);
                sys.index_of[3 * a] != NONE && sys.index_of[3 * b] != NONE
            })
            .collect();
        if live.is_empty() {
            return Ok(x0.to_vec());
        }
        for &p in &live {
            let st = &mut self.state.joints[p];
            if !st.paired {
                *st = JointPointState {
                    paired: true,
                    gap: self.initial_gap,
                    force: [0.0; 3],
                    state: PointState::Open,
                };
            }
        }
        // Cᵀ: column 3q+k = relative displacement of B − A along local axis k.
        let m = 3 * live.len();
        let mut ct = faer::Mat::<f64>::zeros(n, m);
        for (q, &p) in live.iter().enumerate() {
            let pt = &self.points[p];
            let axes = [pt.frame.t1, pt.frame.t2, pt.frame.n];
            for (k, e) in axes.iter().enumerate() {
                for c in 0..3 {
                    let ib = sys.index_of[3 * pt.b as usize + c] as usize;
                    let ia = sys.index_of[3 * pt.a as usize + c] as usize;
                    if !sys.fixed[ib] {
                        ct[(ib, 3 * q + k)] += e[c];
                    }
                    if !sys.fixed[ia] {
                        ct[(ia, 3 * q + k)] -= e[c];
                    }
                }
            }
        }
        let mut minv_ct = ct.clone();
        sys.solver
            .solve_columns(&mut minv_ct)
            .map_err(|source| MechError::Solve { day, source })?;
        let w_faer = ct.transpose() * &minv_ct;
        let w = nalgebra::DMatrix::from_fn(m, m, |i, j| 0.5 * (w_faer[(i, j)] + w_faer[(j, i)]));
        let r_old: Vec<f64> = live
            .iter()
            .flat_map(|&p| self.state.joints[p].force)
            .collect();
        // Free increment with the old contact forces removed.
        let mut du0 = x0.to_vec();
        for i in 0..n {
            du0[i] -= (0..m).map(|k| minv_ct[(i, k)] * r_old[k]).sum::<f64>();
        }
        let mut bvec = vec![0.0; m];
        for k in 0..m {
            bvec[k] = (0..n).map(|i| ct[(i, k)] * du0[i]).sum::<f64>();
        }
        for (q, &p) in live.iter().enumerate() {
            bvec[3 * q + 2] += self.state.joints[p].gap;
        }
        let friction = vec![self.friction; live.len()];
        let problem = ContactProblem::new(&w, &bvec, &friction);
        let sol = crate::joint::solve(&problem, &ContactSettings::default(), Some(&r_old))
            .map_err(|source| MechError::Contact { day, source })?;
        let mut x = du0;
        for i in 0..n {
            x[i] += (0..m).map(|k| minv_ct[(i, k)] * sol.r[k]).sum::<f64>();
        }
        // Contact forces on the nodes (total), for the equilibrium check.
        self.state.f_contact.iter_mut().for_each(|f| *f = 0.0);
        for (q, &p) in live.iter().enumerate() {
            let pt = &self.points[p];
            let st = &mut self.state.joints[p];
            st.force = [sol.r[3 * q], sol.r[3 * q + 1], sol.r[3 * q + 2]];
            st.gap = sol.u[3 * q + 2];
            st.state = sol.states[q].into();
            let global = pt.frame.to_global(st.force);
            for c in 0..3 {
                self.state.f_contact[3 * pt.b as usize + c] += global[c];
                self.state.f_contact[3 * pt.a as usize + c] -= global[c];
            }
        }
        Ok(x)
    }

    /// ‖Σ Bᵀσ − f_ext‖ / ‖f_ext‖ (or the internal-force scale when no load)
    /// over the free live dofs: the accumulated stresses must balance the
    /// accumulated loads.
    pub fn equilibrium_residual(&self) -> f64 {
        let Some(sys) = &self.sys else { return 0.0 };
        let mut fint = vec![0.0; self.state.u.len()];
        let mut scale = 0.0f64;
        for &e in &sys.elems {
            let e = e as usize;
            let f = elasticity::internal_force(&self.gauss[e], &self.state.stress[e]);
            let gd = elasticity::element_dofs(&self.elements[e]);
            for k in 0..24 {
                fint[gd[k] as usize] += f[k];
                scale = scale.max(f[k].abs());
            }
        }
        let (mut r2, mut f2) = (0.0, 0.0);
        for (i, &d) in sys.dofs.iter().enumerate() {
            if sys.fixed[i] {
                continue;
            }
            let f = self.state.f_ext[d as usize] + self.state.f_contact[d as usize];
            let r = fint[d as usize] - f;
            r2 += r * r;
            f2 += f * f;
        }
        r2.sqrt() / f2.sqrt().max(scale).max(f64::MIN_POSITIVE)
    }

    /// Number of live mechanical dofs.
    pub fn live_dofs(&self) -> usize {
        self.sys.as_ref().map_or(0, |s| s.dofs.len())
    }
}
