//! The staged transient heat problem of the live elements.

use std::collections::HashMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::solver::SolveError;
use crate::material::{AdiabaticRise, ZhuPipe};
use crate::mesh::{Mesh, Part, SurfaceKind, ZonePoint};
use crate::scene::{CapacityKind, Effect, Scene, ThermalSolverKind};

use super::boundary::{AirTemperature, Water};
use super::cooling::{lift_increment, ActiveStage, LiftSourceInput, PlannedStage, StageStatus};
use super::elements::{ElementData, SECONDS_PER_DAY};
use super::ledger::HeatLedger;
use super::live::{FaceCounter, LiveSystem, NONE};

/// Relative residual above which a solve is rejected.
const RESIDUAL_TOLERANCE: f64 = 1e-9;

/// Errors of the thermal step.
#[derive(Debug, thiserror::Error)]
pub enum ThermalError {
    #[error("thermal solve failed on day {day:.3} (step {dt} d): {source}")]
    Solve {
        day: f64,
        dt: f64,
        source: SolveError,
    },
    #[error("thermal solve on day {day:.3}: relative residual {residual:.3e} exceeds {RESIDUAL_TOLERANCE:.0e}")]
    Residual { day: f64, residual: f64 },
    #[error("thermal PCG on day {day:.3} (step {dt} d) stopped after {iterations} iterations at relative residual {residual:.3e}")]
    NotConverged {
        day: f64,
        dt: f64,
        iterations: usize,
        residual: f64,
    },
    #[error("thermal solve on day {day:.3} produced a non-finite temperature")]
    NonFinite { day: f64 },
    #[error("element data: {0}")]
    ElementData(#[from] super::elements::ElementDataError),
    #[error("boundary faces on day {day:.3}: {source}")]
    Face {
        day: f64,
        source: crate::fem::ElementError,
    },
}

/// Counters a benchmark prints; nothing here changes the answer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ThermalStats {
    pub steps: usize,
    /// live-set rebuilds (new pattern + symbolic factorisation)
    pub symbolic: usize,
    /// numeric factorisations
    pub numeric: usize,
    /// boundary matrix reassemblies (births or water-level changes)
    pub assemblies: usize,
    /// evaluations of pipe-cooling source terms (lift × step)
    pub pipe_terms: usize,
    /// conjugate-gradient iterations (PCG solver)
    pub pcg_iterations: usize,
    pub seconds_symbolic: f64,
    pub seconds_numeric: f64,
    pub seconds_solve: f64,
    pub seconds_assembly: f64,
    pub max_dofs: usize,
}

/// Checkpointable part of the thermal problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalState {
    /// per thermal dof; meaningful only where a live element uses the dof
    pub temperature: Vec<f64>,
    pub live: Vec<bool>,
    pub status: Vec<StageStatus>,
    pub ledger: HeatLedger,
}

/// A thermal model's restart data ([`ThermalModel::checkpoint`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalCheckpoint {
    pub state: ThermalState,
    pub stages: Vec<PlannedStage>,
    /// (block, lift, pour day)
    pub lift_pour_day: Vec<(u32, u32, f64)>,
}

pub struct ThermalModel {
    pub data: ElementData,
    rise: Option<AdiabaticRise>,
    pipe: Option<ZhuPipe>,
    air: Option<AirTemperature>,
    water: Option<Water>,
    theta: f64,
    consistent: bool,
    solver: crate::scene::SolverSettings,
    surface_kind: HashMap<(u32, u8), SurfaceKind>,
    dof_z: Vec<f64>,
    dof_xyz: Vec<[f64; 3]>,
    lift_elems: HashMap<(u32, u32), Vec<u32>>,
    lift_pour_day: HashMap<(u32, u32), f64>,
    pub stages: Vec<PlannedStage>,
    /// per lift, index of the stage running on it
    lift_stage: HashMap<(u32, u32), usize>,
    faces: FaceCounter,
    sys: Option<LiveSystem>,
    dirty: bool,
    pub state: ThermalState,
    pub stats: ThermalStats,
}

impl ThermalModel {
    /// Builds the thermal model; rock elements are born at day 0 with the
    /// rock's initial field. `stages` come from cooling.csv and are ignored
    /// unless the scene has the `pipe_cooling` effect.
    pub fn new(
        mesh: &Mesh,
        scene: &Scene,
        stages: Vec<PlannedStage>,
        air: Option<AirTemperature>,
        water: Option<Water>,
    ) -> Result<ThermalModel, ThermalError> {
        let data = ElementData::new(mesh, scene)?;
        let pipe = if scene.has(Effect::PipeCooling) {
            scene.pipes.as_ref().map(|layout| {
                ZhuPipe::new(
                    layout,
                    scene.concrete_diffusivity_m2_per_day(),
                    scene.concrete.conductivity_w_mk,
                )
            })
        } else {
            None
        };
        let stages = if pipe.is_some() { stages } else { Vec::new() };
        let mut dof_xyz = vec![[0.0; 3]; mesh.n_thermal_dofs];
        for (node, &d) in mesh.thermal_dof.iter().enumerate() {
            dof_xyz[d as usize] = mesh.nodes[node];
        }
        let dof_z = dof_xyz.iter().map(|p| p[2]).collect();
        let mut lift_elems: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (e, part) in mesh.parts.iter().enumerate() {
            if let Part::Concrete { block, lift } = part {
                lift_elems
                    .entry((*block, *lift))
                    .or_default()
                    .push(e as u32);
            }
        }
        let surface_kind = mesh
            .surfaces
            .iter()
            .map(|s| ((s.elem, s.face), s.kind))
            .collect();
        let n_elem = mesh.elements.len();
        let status = vec![StageStatus::Pending; stages.len()];
        let mut model = ThermalModel {
            data,
            rise: if scene.has(Effect::Hydration) {
                scene.concrete.adiabatic.clone()
            } else {
                None
            },
            pipe,
            air: if scene.has(Effect::Ambient) {
                air
            } else {
                None
            },
            water: if scene.has(Effect::ReservoirTemperature) {
                water
            } else {
                None
            },
            theta: scene.time.theta,
            consistent: scene.time.capacity == CapacityKind::Consistent,
            solver: scene.solver.clone(),
            surface_kind,
            dof_z,
            dof_xyz,
            lift_elems,
            lift_pour_day: HashMap::new(),
            stages,
            lift_stage: HashMap::new(),
            faces: FaceCounter::default(),
            sys: None,
            dirty: true,
            state: ThermalState {
                temperature: vec![0.0; mesh.n_thermal_dofs],
                live: vec![false; n_elem],
                status,
                ledger: HeatLedger::default(),
            },
            stats: ThermalStats::default(),
        };
        if let Some(rock) = &scene.rock {
            let z_ref = mesh.layer_z.first().copied().unwrap_or(0.0);
            let rock_elems: Vec<u32> = (0..n_elem as u32)
                .filter(|&e| mesh.parts[e as usize] == Part::Rock)
                .collect();
            let (t0, g) = (rock.initial_temp_c, rock.gradient_c_per_m);
            model.birth(&rock_elems, |z| t0 + g * (z_ref - z));
        }
        Ok(model)
    }

    /// Makes `elems` live; dofs not yet live take `initial(z)`.
    fn birth(&mut self, elems: &[u32], initial: impl Fn(f64) -> f64) {
        let live_dof = self.live_dofs_mask();
        for &e in elems {
            for &d in &self.data.dofs[e as usize] {
                if !live_dof[d as usize] {
                    self.state.temperature[d as usize] = initial(self.dof_z[d as usize]);
                }
            }
        }
        for &e in elems {
            self.state.live[e as usize] = true;
            self.faces.add_element(e, &self.data.dofs[e as usize]);
            self.state.ledger.births += self.data.stored_heat(e as usize, &self.state.temperature);
        }
        self.dirty = true;
    }

    fn live_dofs_mask(&self) -> Vec<bool> {
        let mut mask = vec![false; self.state.temperature.len()];
        for (e, &live) in self.state.live.iter().enumerate() {
            if live {
                for &d in &self.data.dofs[e] {
                    mask[d as usize] = true;
                }
            }
        }
        mask
    }

    /// Pours lift `lift` of `block` on `day` at `placement_c`.
    pub fn pour(&mut self, block: u32, lift: u32, day: f64, placement_c: f64) {
        let elems = self
            .lift_elems
            .get(&(block, lift))
            .cloned()
            .unwrap_or_default();
        self.lift_pour_day.insert((block, lift), day);
        self.birth(&elems, |_| placement_c);
    }

    /// Starts the stages that begin on `day` and ends those that end on `day`.
    /// Returns true if any stage changed.
    pub fn update_stages(&mut self, day: f64) -> bool {
        let mut changed = false;
        for i in 0..self.stages.len() {
            let st = &self.stages[i];
            match self.state.status[i] {
                StageStatus::Pending if st.start_day <= day => {
                    if st.end_day.is_some_and(|end| end <= day) {
                        self.state.status[i] = StageStatus::Done {
                            end_day: day,
                            reached_target: false,
                        };
                        continue;
                    }
                    let t0_mean = self.region_mean(i);
                    for lift in st.lift_from..=st.lift_to {
                        self.lift_stage.insert((st.block, lift), i);
                    }
                    let armed = st.target_temp_c.is_some_and(|target| t0_mean > target);
                    self.state.status[i] = StageStatus::Active {
                        start_day: day,
                        t0_mean,
                        armed,
                    };
                    changed = true;
                }
                StageStatus::Active { .. } if st.end_day.is_some_and(|end| end <= day) => {
                    self.end_stage(i, day, false);
                    changed = true;
                }
                _ => {}
            }
        }
        changed
    }

    fn end_stage(&mut self, i: usize, day: f64, reached_target: bool) {
        let st = &self.stages[i];
        for lift in st.lift_from..=st.lift_to {
            if self.lift_stage.get(&(st.block, lift)) == Some(&i) {
                self.lift_stage.remove(&(st.block, lift));
            }
        }
        self.state.status[i] = StageStatus::Done {
            end_day: day,
            reached_target,
        };
    }

    /// Capacity-weighted mean temperature of a stage's region.
    pub fn region_mean(&self, stage: usize) -> f64 {
        let st = &self.stages[stage];
        let (mut heat, mut cap) = (0.0, 0.0);
        for lift in st.lift_from..=st.lift_to {
            for &e in self
                .lift_elems
                .get(&(st.block, lift))
                .map(|v| v.as_slice())
                .unwrap_or(&[])
            {
                if self.state.live[e as usize] {
                    heat += self.data.stored_heat(e as usize, &self.state.temperature);
                    cap += self.data.cap_lumped[e as usize].iter().sum::<f64>();
                }
            }
        }
        if cap > 0.0 {
            heat / cap
        } else {
            f64::NAN
        }
    }

    /// Capacity-weighted mean temperature of lifts `from..=to` of `block`,
    /// if every one of them is live.
    pub fn lifts_mean(&self, block: u32, from: u32, to: u32) -> Option<f64> {
        let (mut heat, mut cap) = (0.0, 0.0);
        for lift in from..=to {
            for &e in self.lift_elems.get(&(block, lift))? {
                if !self.state.live[e as usize] {
                    return None;
                }
                heat += self.data.stored_heat(e as usize, &self.state.temperature);
                cap += self.data.cap_lumped[e as usize].iter().sum::<f64>();
            }
        }
        (cap > 0.0).then(|| heat / cap)
    }

    /// What a restart needs besides the schedules: the state, the stages as
    /// they were planned (to match statuses to a new cooling.csv) and the
    /// pour days.
    pub fn checkpoint(&self) -> ThermalCheckpoint {
        let mut lift_pour_day: Vec<(u32, u32, f64)> = self
            .lift_pour_day
            .iter()
            .map(|(&(b, l), &d)| (b, l, d))
            .collect();
        lift_pour_day.sort_by_key(|&(b, l, _)| (b, l));
        ThermalCheckpoint {
            state: self.state.clone(),
            stages: self.stages.clone(),
            lift_pour_day,
        }
    }

    /// Restores a checkpoint into a model built for (possibly edited)
    /// schedules. A stage of the new cooling.csv takes the status of the
    /// checkpoint's stage with the same block, lifts, kind of rows and start;
    /// a stage with no match must start on or after the checkpoint's day
    /// (the caller restarts before the first changed date) and is pending.
    pub fn restore(&mut self, ck: &ThermalCheckpoint) {
        let key = |st: &PlannedStage| (st.block, st.lift_from, st.lift_to, st.start_day.to_bits());
        let old: HashMap<_, &StageStatus> = ck
            .stages
            .iter()
            .zip(&ck.state.status)
            .map(|(st, status)| (key(st), status))
            .collect();
        let status: Vec<StageStatus> = self
            .stages
            .iter()
            .map(|st| {
                old.get(&key(st))
                    .map_or(StageStatus::Pending, |s| (*s).clone())
            })
            .collect();
        self.state = ThermalState {
            status,
            ..ck.state.clone()
        };
        self.lift_pour_day = ck
            .lift_pour_day
            .iter()
            .map(|&(b, l, d)| ((b, l), d))
            .collect();
        // A later stage on a lift ends the one before it: replay the starts in order.
        let mut active: Vec<(f64, usize)> = self
            .state
            .status
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match s {
                StageStatus::Active { start_day, .. } => Some((*start_day, i)),
                _ => None,
            })
            .collect();
        active.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.lift_stage.clear();
        for (_, i) in active {
            let st = &self.stages[i];
            for lift in st.lift_from..=st.lift_to {
                self.lift_stage.insert((st.block, lift), i);
            }
        }
        self.faces = FaceCounter::default();
        for (e, &live) in self.state.live.iter().enumerate() {
            if live {
                self.faces.add_element(e as u32, &self.data.dofs[e]);
            }
        }
        self.sys = None;
        self.dirty = true;
    }

    /// Mean temperature of the concrete of (block, lift) elements, if live.
    pub fn lift_mean(&self, block: u32, lift: u32) -> Option<f64> {
        let elems = self.lift_elems.get(&(block, lift))?;
        let (mut heat, mut cap) = (0.0, 0.0);
        for &e in elems {
            if !self.state.live[e as usize] {
                return None;
            }
            heat += self.data.stored_heat(e as usize, &self.state.temperature);
            cap += self.data.cap_lumped[e as usize].iter().sum::<f64>();
        }
        (cap > 0.0).then(|| heat / cap)
    }

    fn rebuild(&mut self) -> Result<(), SolveError> {
        let t = Instant::now();
        let live: Vec<u32> = (0..self.state.live.len() as u32)
            .filter(|&e| self.state.live[e as usize])
            .collect();
        let exposed = if self.air.is_some() || self.water.is_some() {
            self.faces.exposed(&self.surface_kind)
        } else {
            Vec::new()
        };
        let direct = self.solver.thermal == ThermalSolverKind::Cholesky;
        let sys = LiveSystem::new(
            &self.dof_xyz,
            live,
            &self.data,
            exposed,
            self.consistent,
            direct,
        )?;
        if direct {
            self.stats.symbolic += 1;
        }
        self.stats.max_dofs = self.stats.max_dofs.max(sys.n());
        self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
        self.sys = Some(sys);
        self.dirty = false;
        Ok(())
    }

    fn beta_day(&self) -> Option<f64> {
        self.air.as_ref().map(|a| a.film_w_m2k() * SECONDS_PER_DAY)
    }

    /// Prescribed water temperatures at `day` on submerged wet-face nodes.
    fn water_nodes(&self, sys: &LiveSystem, day: f64) -> (Vec<bool>, Vec<f64>) {
        let n = sys.n();
        let mut fixed = vec![false; n];
        let mut value = vec![0.0; n];
        let (Some(water), Some(level)) =
            (&self.water, self.water.as_ref().and_then(|w| w.level(day)))
        else {
            return (fixed, value);
        };
        for f in sys.exposed.iter().filter(|f| f.wet) {
            for &k in &crate::fem::hex8::FACES[f.face as usize] {
                let d = self.data.dofs[f.elem as usize][k];
                let z = self.dof_z[d as usize];
                if z <= level {
                    let i = sys.index_of[d as usize] as usize;
                    fixed[i] = true;
                    value[i] = water.temperature(day, level - z);
                }
            }
        }
        (fixed, value)
    }

    /// Advances from t0 to t1 (days). Sources, boundary values and the
    /// submerged set are those of the step; stages ending by target are
    /// closed at t1.
    pub fn step(&mut self, t0: f64, t1: f64) -> Result<(), ThermalError> {
        let dt = t1 - t0;
        let theta = self.theta;
        if self.dirty {
            self.rebuild().map_err(|source| ThermalError::Solve {
                day: t1,
                dt,
                source,
            })?;
            let beta = self.beta_day();
            let t = Instant::now();
            let sys = self.sys.as_mut().expect("rebuilt");
            sys.assemble_kh(&self.data, beta)
                .map_err(|source| ThermalError::Face { day: t1, source })?;
            self.stats.assemblies += 1;
            self.stats.seconds_assembly += t.elapsed().as_secs_f64();
        }
        let (fixed, fixed_value) = self.water_nodes(self.sys.as_ref().expect("built"), t1);
        if fixed != self.sys.as_ref().expect("built").fixed {
            let beta = self.beta_day();
            let t = Instant::now();
            let sys = self.sys.as_mut().expect("built");
            sys.fixed = fixed;
            sys.assemble_kh(&self.data, beta)
                .map_err(|source| ThermalError::Face { day: t1, source })?;
            self.stats.assemblies += 1;
            self.stats.seconds_assembly += t.elapsed().as_secs_f64();
        }

        // Heat sources of the step, per live dof [J].
        let sys = self.sys.as_ref().expect("built");
        let n = sys.n();
        let mut q = vec![0.0; n];
        let (mut hyd_heat, mut pipe_heat) = (0.0, 0.0);
        if self.rise.is_some() || self.pipe.is_some() {
            for (&(block, lift), &pour_day) in &self.lift_pour_day {
                if pour_day > t0 {
                    continue;
                }
                let stage = self.lift_stage.get(&(block, lift)).and_then(|&i| {
                    match (&self.state.status[i], &self.pipe) {
                        (
                            StageStatus::Active {
                                start_day, t0_mean, ..
                            },
                            Some(pipe),
                        ) => Some(ActiveStage {
                            pipe,
                            start_day: *start_day,
                            t0_mean: *t0_mean,
                            water_temp_c: self.stages[i].water_temp_c,
                        }),
                        _ => None,
                    }
                });
                if stage.is_some() {
                    self.stats.pipe_terms += 1;
                }
                let inc = lift_increment(
                    &LiftSourceInput {
                        pour_day,
                        rise: self.rise.as_ref(),
                        stage,
                    },
                    t0,
                    t1,
                );
                if inc.total == 0.0 && inc.hydration == 0.0 {
                    continue;
                }
                for &e in &self.lift_elems[&(block, lift)] {
                    let caps = &self.data.cap_lumped[e as usize];
                    for (k, &d) in self.data.dofs[e as usize].iter().enumerate() {
                        q[sys.index_of[d as usize] as usize] += caps[k] * inc.total;
                    }
                    let c: f64 = caps.iter().sum();
                    hyd_heat += c * inc.hydration;
                    pipe_heat += c * (inc.total - inc.hydration);
                }
            }
        }

        // Air temperature weighted by θ over the step.
        let ta = self
            .air
            .as_ref()
            .map(|a| theta * a.at(t1) + (1.0 - theta) * a.at(t0))
            .unwrap_or(0.0);

        let t_old: Vec<f64> = sys
            .dofs
            .iter()
            .map(|&d| self.state.temperature[d as usize])
            .collect();
        // b = C T0 − (1−θ)Δt KH T0 + Δt f_θ + Q
        let mut b = vec![0.0; n];
        sys.cap_mul(&t_old, &mut b);
        let mut kh_t = vec![0.0; n];
        if theta < 1.0 {
            sys.kh.mul_vec(&t_old, &mut kh_t);
        }
        for i in 0..n {
            b[i] += -(1.0 - theta) * dt * kh_t[i] + dt * ta * sys.air_load[i] + q[i];
        }
        let b_full = b.clone();
        // Move prescribed values to the right-hand side: b_free −= A_{free,fixed} x_fixed.
        if sys.fixed.iter().any(|&f| f) {
            let xf: Vec<f64> = (0..n)
                .map(|i| if sys.fixed[i] { fixed_value[i] } else { 0.0 })
                .collect();
            let mut y = vec![0.0; n];
            let mut ky = vec![0.0; n];
            sys.cap_mul(&xf, &mut y);
            sys.kh.mul_vec(&xf, &mut ky);
            for i in 0..n {
                if sys.fixed[i] {
                    b[i] = fixed_value[i];
                } else {
                    b[i] -= y[i] + theta * dt * ky[i];
                }
            }
        }

        let x = match self.solver.thermal {
            ThermalSolverKind::Cholesky => {
                let sys = self.sys.as_mut().expect("built");
                let t = Instant::now();
                let (factor, fresh) =
                    sys.factor(dt, theta)
                        .map_err(|source| ThermalError::Solve {
                            day: t1,
                            dt,
                            source,
                        })?;
                if fresh {
                    self.stats.numeric += 1;
                    self.stats.seconds_numeric += t.elapsed().as_secs_f64();
                }
                let mut x = b;
                let t_solve = Instant::now();
                factor
                    .solve_in_place(&mut x)
                    .map_err(|source| ThermalError::Solve {
                        day: t1,
                        dt,
                        source,
                    })?;
                self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
                x
            }
            ThermalSolverKind::Pcg => {
                let sys = self.sys.as_ref().expect("built");
                let t_solve = Instant::now();
                // Start from the old temperatures; prescribed values are exact already.
                let mut x: Vec<f64> = (0..n)
                    .map(|i| if sys.fixed[i] { b[i] } else { t_old[i] })
                    .collect();
                let max = self.solver.pcg_max_iterations as usize;
                let iterations = sys
                    .solve_pcg(dt, theta, &b, &mut x, self.solver.pcg_tolerance, max)
                    .map_err(|residual| ThermalError::NotConverged {
                        day: t1,
                        dt,
                        iterations: max,
                        residual,
                    })?;
                self.stats.pcg_iterations += iterations;
                self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
                x
            }
        };
        if x.iter().any(|v| !v.is_finite()) {
            return Err(ThermalError::NonFinite { day: t1 });
        }

        // Residual of the unmodified equations on free rows; reactions on fixed rows:
        // r = C T1 + θΔt KH T1 − b_full, where b_full = C T0 − (1−θ)Δt KH T0 + Δt f_θ + Q.
        let sys = self.sys.as_ref().expect("built");
        let mut c_new = vec![0.0; n];
        sys.cap_mul(&x, &mut c_new);
        let mut kh_new = vec![0.0; n];
        sys.kh.mul_vec(&x, &mut kh_new);
        let (mut res2, mut ref2, mut water_heat) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let r = c_new[i] + theta * dt * kh_new[i] - b_full[i];
            if sys.fixed[i] {
                water_heat += r;
            } else {
                res2 += r * r;
                ref2 += b_full[i] * b_full[i] + c_new[i] * c_new[i];
            }
        }
        let residual = (res2 / ref2.max(f64::MIN_POSITIVE)).sqrt();
        if residual > RESIDUAL_TOLERANCE {
            return Err(ThermalError::Residual { day: t1, residual });
        }
        // Air heat = Δt Σ (f_θ − H T_θ); Σ_i (KH T_θ)_i = Σ_i (H T_θ)_i because K
        // annihilates constants (K is symmetric with zero row sums).
        let kh_theta_sum: f64 = (0..n)
            .map(|i| theta * kh_new[i] + (1.0 - theta) * kh_t[i])
            .sum();
        let air_heat = dt * ta * sys.air_load.iter().sum::<f64>() - dt * kh_theta_sum;

        for (i, &d) in sys.dofs.iter().enumerate() {
            self.state.temperature[d as usize] = x[i];
        }
        let ledger = &mut self.state.ledger;
        ledger.hydration += hyd_heat;
        ledger.pipes += pipe_heat;
        ledger.air += air_heat;
        ledger.water += water_heat;
        self.stats.steps += 1;

        // Stages whose region has fallen to its target end now.
        for i in 0..self.stages.len() {
            let (StageStatus::Active { armed, .. }, Some(target)) =
                (self.state.status[i].clone(), self.stages[i].target_temp_c)
            else {
                continue;
            };
            let mean = self.region_mean(i);
            if armed && mean <= target {
                self.end_stage(i, t1, true);
            } else if !armed && mean > target {
                if let StageStatus::Active { armed, .. } = &mut self.state.status[i] {
                    *armed = true;
                }
            }
        }
        Ok(())
    }

    /// Stored heat Σ c_i T_i of the live dofs [J].
    pub fn stored_heat(&self) -> f64 {
        (0..self.state.live.len())
            .filter(|&e| self.state.live[e])
            .map(|e| self.data.stored_heat(e, &self.state.temperature))
            .sum()
    }

    /// Temperature at a zone point (bilinear on the joint face), if its nodes are live.
    pub fn point_temperature(&self, mesh: &Mesh, p: &ZonePoint) -> Option<f64> {
        let pair = &mesh.face_pairs[p.pair as usize];
        let sys = self.sys.as_ref()?;
        let n = crate::fem::quad4::shape([p.s, p.t]);
        let mut value = 0.0;
        for (k, &node) in pair.nodes_a.iter().enumerate() {
            let d = mesh.thermal_dof[node as usize];
            if sys.index_of[d as usize] == NONE {
                return None;
            }
            value += n[k] * self.state.temperature[d as usize];
        }
        Some(value)
    }

    /// Temperature of every mesh node (joint duplicates share their dof), NaN where not live.
    pub fn nodal_field(&self, mesh: &Mesh) -> Vec<f64> {
        let mask = self.live_dofs_mask();
        mesh.thermal_dof
            .iter()
            .map(|&d| {
                if mask[d as usize] {
                    self.state.temperature[d as usize]
                } else {
                    f64::NAN
                }
            })
            .collect()
    }

    pub fn has_pipes(&self) -> bool {
        self.pipe.is_some()
    }
}
