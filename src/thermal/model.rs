//! The staged transient heat problem of the live elements.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fem::solver::SolveError;
use crate::mesh::{Mesh, Part, SurfaceKind, ZoneSite};
use crate::scene::{CapacityKind, ThermalSolverKind};

use super::boundary::{AirTemperature, Water};
use super::cooling::{lift_increment, ActiveStage, LiftSourceInput, PlannedStage, StageStatus};
use super::elements::{ElementData, SECONDS_PER_DAY};
use super::ledger::HeatLedger;
use super::live::{FaceCounter, LiveSystem};
use super::settings::ThermalSettings;

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

/// Water warmer than the cooled region by more than this when its stage
/// starts is a warning: the pipes then warm the concrete markedly (a few
/// degrees above it is the "holding" water of an intermediate stage).
pub const WARM_WATER_MARGIN_C: f64 = 5.0;

/// A stage without an end date still waiting for its region to rise above
/// its target this many days after it started is a warning.
pub const UNUSED_TARGET_DAYS: f64 = 30.0;

/// The step length t1 − t0 on a grid of 2⁻³⁶ d (1.3 µs). Days accumulated
/// by repeated addition differ in their last bits (0.1 d steps give nine
/// different differences near 0.1), and the factor cache is keyed by the
/// exact bits of Δt: on the grid they are one length again. The change is
/// below 1e-10 of any step and is used for the matrix and the right-hand
/// side alike.
pub fn step_length(t0: f64, t1: f64) -> f64 {
    const GRID: f64 = (1u64 << 36) as f64;
    ((t1 - t0) * GRID).round() / GRID
}

impl ThermalError {
    /// The unknown (in the live system's numbering) whose pivot failed.
    pub fn pivot_dof(&self) -> Option<usize> {
        match self {
            ThermalError::Solve { source, .. } => source.pivot_dof(),
            _ => None,
        }
    }
}

/// Counters a benchmark prints; nothing here changes the answer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ThermalStats {
    /// steps taken
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
    /// wall time of the rebuilds \[s\]
    pub seconds_symbolic: f64,
    /// wall time of the numeric factorisations \[s\]
    pub seconds_numeric: f64,
    /// wall time of the solves (triangular or PCG) \[s\]
    pub seconds_solve: f64,
    /// wall time of the boundary reassemblies \[s\]
    pub seconds_assembly: f64,
    /// largest live system \[dofs\]
    pub max_dofs: usize,
}

/// Checkpointable part of the thermal problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalState {
    /// per thermal dof; meaningful only where a live element uses the dof
    pub temperature: Vec<f64>,
    /// per element: born (poured, or rock)
    pub live: Vec<bool>,
    /// per planned cooling stage
    pub status: Vec<StageStatus>,
    /// heat gained so far, by source
    pub ledger: HeatLedger,
    /// stages whose water was warmer than their region's mean by more than
    /// [`WARM_WATER_MARGIN_C`] when they started: (stage, mean at start °C)
    #[serde(default)]
    pub warm_water: Vec<(usize, f64)>,
}

/// A thermal model's restart data ([`ThermalModel::checkpoint`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalCheckpoint {
    pub state: ThermalState,
    pub stages: Vec<PlannedStage>,
    /// (block, lift, pour day)
    pub lift_pour_day: Vec<(u32, u32, f64)>,
}

/// What a thermal step changes of a model whose live set stays (between
/// two days' events): the state and the stage running on each lift. A
/// driver that steps the model ahead of a decision keeps one of the day it
/// decides on, and swaps it in ([`ThermalModel::swap_rewind`]) to show or
/// go back to that day. The live system and its factors are caches of the
/// same live set and serve either day alike; the counters keep the work done.
#[derive(Debug, Clone)]
pub struct ThermalRewind {
    state: ThermalState,
    lift_stage: BTreeMap<(u32, u32), usize>,
}

impl ThermalRewind {
    /// The temperature per thermal dof on its day.
    pub fn temperature(&self) -> &[f64] {
        &self.state.temperature
    }
}

pub struct ThermalModel {
    pub data: ElementData,
    settings: ThermalSettings,
    air: Option<AirTemperature>,
    water: Option<Water>,
    surface_kind: BTreeMap<(u32, u8), SurfaceKind>,
    /// Per thermal dof, the fixed temperature of the far side it lies on
    /// (`[boundary]`); empty when every far side is adiabatic.
    far_fixed: Vec<Option<f64>>,
    dof_z: Vec<f64>,
    dof_xyz: Vec<[f64; 3]>,
    lift_elems: BTreeMap<(u32, u32), Vec<u32>>,
    /// (block, lift) → pour day. Ordered: [`ThermalModel::sources`] adds the
    /// lifts' heat into shared dofs in this order, and a hash map's order
    /// (random per process) would change the sums' round-off run to run.
    lift_pour_day: BTreeMap<(u32, u32), f64>,
    pub stages: Vec<PlannedStage>,
    /// per lift, index of the stage running on it
    lift_stage: BTreeMap<(u32, u32), usize>,
    faces: FaceCounter,
    /// the system of the live set at the last rebuild (empty before the
    /// first step and after a restore)
    sys: LiveSystem,
    /// the live set has changed since `sys` was built
    dirty: bool,
    pub state: ThermalState,
    pub stats: ThermalStats,
}

impl ThermalModel {
    /// The thermal dof of an unknown of the current live system.
    pub fn dof_of_unknown(&self, i: usize) -> Option<u32> {
        self.sys.dofs.get(i).copied()
    }

    /// Builds the thermal model; rock elements are born at day 0 with the
    /// rock's initial field. `stages` come from cooling.csv and are ignored
    /// without pipe cooling (`settings.pipe`); `air` and `water` are ignored
    /// without their effects.
    pub fn new(
        mesh: &Mesh,
        settings: &ThermalSettings,
        stages: Vec<PlannedStage>,
        air: Option<AirTemperature>,
        water: Option<Water>,
    ) -> Result<ThermalModel, ThermalError> {
        let data = ElementData::new(mesh, settings)?;
        let stages = if settings.pipe.is_some() {
            stages
        } else {
            Vec::new()
        };
        let mut dof_xyz = vec![[0.0; 3]; mesh.n_thermal_dofs];
        for (node, &d) in mesh.thermal_dof.iter().enumerate() {
            dof_xyz[d as usize] = mesh.nodes[node];
        }
        let dof_z = dof_xyz.iter().map(|p| p[2]).collect();
        let surface_kind = mesh
            .surfaces
            .iter()
            .map(|s| ((s.elem, s.face), s.kind))
            .collect();
        let n_elem = mesh.elements.len();
        let status = vec![StageStatus::Pending; stages.len()];
        let mut model = ThermalModel {
            data,
            settings: settings.clone(),
            air: air.filter(|_| settings.ambient),
            water: water.filter(|_| settings.reservoir_temperature),
            surface_kind,
            far_fixed: far_fixed(mesh, &settings.far_temperature_c),
            dof_z,
            dof_xyz,
            lift_elems: mesh.lift_elements(),
            lift_pour_day: BTreeMap::new(),
            stages,
            lift_stage: BTreeMap::new(),
            faces: FaceCounter::default(),
            sys: LiveSystem::empty(mesh.n_thermal_dofs),
            dirty: true,
            state: ThermalState {
                temperature: vec![0.0; mesh.n_thermal_dofs],
                live: vec![false; n_elem],
                status,
                ledger: HeatLedger::default(),
                warm_water: Vec::new(),
            },
            stats: ThermalStats::default(),
        };
        if let Some(rock) = &settings.rock {
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
        let live_dof = self.live_dofs();
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

    /// Per thermal dof: used by a live element. Read from the state, not the
    /// live system, so a lift poured today counts before the next step
    /// rebuilds the system.
    pub fn live_dofs(&self) -> Vec<bool> {
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
        if self.settings.placement_on_shared_nodes {
            self.birth_resetting(&elems, placement_c);
        } else {
            self.birth(&elems, |_| placement_c);
        }
    }

    /// Makes `elems` live with every one of their dofs at `placement_c`,
    /// those shared with live elements included; the births' heat is the
    /// change of the stored heat, so the ledger stays exact.
    fn birth_resetting(&mut self, elems: &[u32], placement_c: f64) {
        let before = self.stored_heat();
        for &e in elems {
            for &d in &self.data.dofs[e as usize] {
                self.state.temperature[d as usize] = placement_c;
            }
        }
        for &e in elems {
            self.state.live[e as usize] = true;
            self.faces.add_element(e, &self.data.dofs[e as usize]);
        }
        self.state.ledger.births += self.stored_heat() - before;
        self.dirty = true;
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
                            target_unused: false,
                        };
                        continue;
                    }
                    let t0_mean = self.region_mean(i);
                    for lift in st.lift_from..=st.lift_to {
                        self.lift_stage.insert((st.block, lift), i);
                    }
                    let armed = st.target_on(day).is_some_and(|target| t0_mean > target);
                    if st.water_temp_c > t0_mean + WARM_WATER_MARGIN_C {
                        self.state.warm_water.push((i, t0_mean));
                    }
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
        let target_unused = !reached_target
            && st.target_temp_c.is_some()
            && matches!(
                self.state.status[i],
                StageStatus::Active { armed: false, .. }
            );
        self.state.status[i] = StageStatus::Done {
            end_day: day,
            reached_target,
            target_unused,
        };
    }

    /// The stages whose water was not colder than their region when they
    /// started, with the region's mean temperature then [°C].
    pub fn warm_water(&self) -> impl Iterator<Item = (&PlannedStage, f64)> {
        self.state
            .warm_water
            .iter()
            .map(|&(i, t)| (&self.stages[i], t))
    }

    /// The stages without an end date whose target never came into play:
    /// their region was never warmer than the target, so they ran until a
    /// later stage on the lift started (`true`), or still run at `day`,
    /// [`UNUSED_TARGET_DAYS`] or more after they started (`false`). A stage
    /// with an end date whose target is never reached just runs its planned
    /// length, which is what its row says.
    pub fn unused_targets(&self, day: f64) -> impl Iterator<Item = (&PlannedStage, bool)> {
        self.stages
            .iter()
            .zip(&self.state.status)
            .filter(|(st, _)| st.end_day.is_none() && st.target_temp_c.is_some())
            .enumerate()
            .filter_map(move |(i, (st, status))| match *status {
                StageStatus::Done {
                    target_unused: true,
                    ..
                } => Some((st, true)),
                StageStatus::Active {
                    armed: false,
                    start_day,
                    ..
                } => {
                    // A later stage on its lifts took over (the stage stays
                    // Active in name, with no lift left to cool).
                    let superseded = (st.lift_from..=st.lift_to)
                        .all(|l| self.lift_stage.get(&(st.block, l)) != Some(&i));
                    (superseded || day - start_day >= UNUSED_TARGET_DAYS)
                        .then_some((st, superseded))
                }
                _ => None,
            })
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
        let lift_pour_day: Vec<(u32, u32, f64)> = self
            .lift_pour_day
            .iter()
            .map(|(&(b, l), &d)| (b, l, d))
            .collect();
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
        let old: BTreeMap<_, &StageStatus> = ck
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
        // Stage indices differ between edited schedules: carry the warm-water
        // findings over by the stage's key, like the statuses.
        let warm_water = ck
            .state
            .warm_water
            .iter()
            .filter_map(|&(i, mean)| {
                let k = key(ck.stages.get(i)?);
                let j = self.stages.iter().position(|st| key(st) == k)?;
                Some((j, mean))
            })
            .collect();
        self.state = ThermalState {
            status,
            warm_water,
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
        self.sys = LiveSystem::empty(self.state.temperature.len());
        self.dirty = true;
    }

    /// The state of now, to come back to ([`ThermalRewind`]).
    pub fn rewind_point(&self) -> ThermalRewind {
        ThermalRewind {
            state: self.state.clone(),
            lift_stage: self.lift_stage.clone(),
        }
    }

    /// Exchanges the model's state with `r`'s: after steps without events,
    /// back to the day `r` was taken on (and `r` then holds the later day).
    pub fn swap_rewind(&mut self, r: &mut ThermalRewind) {
        std::mem::swap(&mut self.state, &mut r.state);
        std::mem::swap(&mut self.lift_stage, &mut r.lift_stage);
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

    /// Renumbers the live dofs and analyses the new pattern (after births).
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
        let direct = self.settings.solver == ThermalSolverKind::Cholesky;
        let sys = LiveSystem::new(
            &self.dof_xyz,
            live,
            &self.data,
            exposed,
            self.settings.capacity == CapacityKind::Consistent,
            direct,
        )?;
        if direct {
            self.stats.symbolic += 1;
        }
        self.stats.max_dofs = self.stats.max_dofs.max(sys.n());
        self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
        self.sys = sys;
        self.dirty = false;
        Ok(())
    }

    fn beta_day(&self) -> Option<f64> {
        self.air.as_ref().map(|a| a.film_w_m2k() * SECONDS_PER_DAY)
    }

    /// Prescribed temperatures at `day` on the live system: the water's on
    /// the submerged wet-face nodes, then the far sides' fixed ones (which
    /// win on a node both hold: the model's edge is the user's choice).
    /// Returns (fixed, value, far) per live dof, `far` marking the rows the
    /// far sides hold.
    fn prescribed_nodes(&self, day: f64) -> (Vec<bool>, Vec<f64>, Vec<bool>) {
        let (mut fixed, mut value) = self.water_nodes(day);
        let mut far = vec![false; fixed.len()];
        if !self.far_fixed.is_empty() {
            for (i, &d) in self.sys.dofs.iter().enumerate() {
                if let Some(t) = self.far_fixed[d as usize] {
                    fixed[i] = true;
                    value[i] = t;
                    far[i] = true;
                }
            }
        }
        (fixed, value, far)
    }

    /// Prescribed water temperatures at `day` on the submerged wet-face nodes
    /// of the live system.
    fn water_nodes(&self, day: f64) -> (Vec<bool>, Vec<f64>) {
        let sys = &self.sys;
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
        let dt = step_length(t0, t1);
        let (fixed_value, far_rows) = self.prepare_system(t1, dt)?;
        let sources = self.sources(t0, t1);
        self.stats.pipe_terms += sources.pipe_terms;
        let (rhs, b) = self.right_hand_side(t0, t1, &sources.q, &fixed_value);
        let x = match self.settings.solver {
            ThermalSolverKind::Cholesky => self.solve_direct(b, t1, dt)?,
            ThermalSolverKind::Pcg => self.solve_pcg(&b, &rhs.t_old, t1, dt)?,
        };
        if x.iter().any(|v| !v.is_finite()) {
            return Err(ThermalError::NonFinite { day: t1 });
        }
        let (air_heat, water_heat, far_heat) = self.boundary_heat(&rhs, &x, &far_rows, t1, dt)?;

        for (i, &d) in self.sys.dofs.iter().enumerate() {
            self.state.temperature[d as usize] = x[i];
        }
        let ledger = &mut self.state.ledger;
        ledger.hydration += sources.hydration;
        ledger.pipes += sources.pipes;
        ledger.air += air_heat;
        ledger.water += water_heat;
        ledger.far += far_heat;
        self.stats.steps += 1;
        self.end_stages_at_target(t1);
        Ok(())
    }

    /// Brings the live system up to the step ending at `day`: renumbered
    /// after births, its boundary matrix reassembled when the submerged set
    /// changes. Returns the prescribed temperature per live dof and which
    /// rows the far sides hold.
    fn prepare_system(&mut self, day: f64, dt: f64) -> Result<(Vec<f64>, Vec<bool>), ThermalError> {
        if self.dirty {
            self.rebuild()
                .map_err(|source| ThermalError::Solve { day, dt, source })?;
            self.assemble_boundary(day)?;
        }
        let (fixed, fixed_value, far) = self.prescribed_nodes(day);
        if fixed != self.sys.fixed {
            self.sys.fixed = fixed;
            self.assemble_boundary(day)?;
        }
        Ok((fixed_value, far))
    }

    /// Reassembles K + H_air of the live system for its exposed faces and
    /// fixed nodes.
    fn assemble_boundary(&mut self, day: f64) -> Result<(), ThermalError> {
        let beta = self.beta_day();
        let t = Instant::now();
        self.sys
            .assemble_kh(&self.data, beta)
            .map_err(|source| ThermalError::Face { day, source })?;
        self.stats.assemblies += 1;
        self.stats.seconds_assembly += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// The cooling stage running on a lift, as its pipe source needs it.
    fn active_stage(&self, block: u32, lift: u32) -> Option<ActiveStage<'_>> {
        let i = *self.lift_stage.get(&(block, lift))?;
        match (&self.state.status[i], &self.settings.pipe) {
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
                changes: &self.stages[i].changes,
            }),
            _ => None,
        }
    }

    /// Heat sources of the step over [t0, t1]: hydration and pipe cooling of
    /// every lift poured by t0.
    fn sources(&self, t0: f64, t1: f64) -> StepSources {
        let sys = &self.sys;
        let mut out = StepSources {
            q: vec![0.0; sys.n()],
            hydration: 0.0,
            pipes: 0.0,
            pipe_terms: 0,
        };
        let rise = self.settings.rise.as_ref();
        if rise.is_none() && self.settings.pipe.is_none() {
            return out;
        }
        // In (block, lift) order: lifts share the dofs of their common faces,
        // so the order of the additions below is part of the answer.
        for (&(block, lift), &pour_day) in &self.lift_pour_day {
            if pour_day > t0 {
                continue;
            }
            let stage = self.active_stage(block, lift);
            if stage.is_some() {
                out.pipe_terms += 1;
            }
            let input = LiftSourceInput {
                pour_day,
                rise,
                stage,
            };
            let inc = lift_increment(&input, t0, t1);
            if inc.total == 0.0 && inc.hydration == 0.0 {
                continue;
            }
            for &e in &self.lift_elems[&(block, lift)] {
                let caps = &self.data.cap_lumped[e as usize];
                for (k, &d) in self.data.dofs[e as usize].iter().enumerate() {
                    out.q[sys.index_of[d as usize] as usize] += caps[k] * inc.total;
                }
                let c: f64 = caps.iter().sum();
                out.hydration += c * inc.hydration;
                out.pipes += c * (inc.total - inc.hydration);
            }
        }
        out
    }

    /// The step's right-hand side b = C T0 − (1−θ)Δt KH T0 + Δt f_θ + Q, and
    /// the same with the prescribed temperatures moved to the right (what is
    /// solved).
    fn right_hand_side(
        &self,
        t0: f64,
        t1: f64,
        q: &[f64],
        fixed_value: &[f64],
    ) -> (StepRhs, Vec<f64>) {
        let (sys, theta, dt) = (&self.sys, self.settings.theta, step_length(t0, t1));
        let n = sys.n();
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
        let mut b = vec![0.0; n];
        sys.cap_mul(&t_old, &mut b);
        let mut kh_t = vec![0.0; n];
        if theta < 1.0 {
            sys.kh.mul_vec(&t_old, &mut kh_t);
        }
        for i in 0..n {
            b[i] += -(1.0 - theta) * dt * kh_t[i] + dt * ta * sys.air_load[i] + q[i];
        }
        let full = b.clone();
        if sys.fixed.iter().any(|&f| f) {
            move_prescribed(sys, theta * dt, fixed_value, &mut b);
        }
        let rhs = StepRhs {
            ta,
            t_old,
            kh_t,
            full,
        };
        (rhs, b)
    }

    /// Solves by the cached Cholesky factor of this step length (factorised
    /// now if new).
    fn solve_direct(
        &mut self,
        mut x: Vec<f64>,
        day: f64,
        dt: f64,
    ) -> Result<Vec<f64>, ThermalError> {
        let t = Instant::now();
        let (factor, fresh) = self
            .sys
            .factor(dt, self.settings.theta)
            .map_err(|source| ThermalError::Solve { day, dt, source })?;
        if fresh {
            self.stats.numeric += 1;
            self.stats.seconds_numeric += t.elapsed().as_secs_f64();
        }
        let t_solve = Instant::now();
        factor
            .solve_in_place(&mut x)
            .map_err(|source| ThermalError::Solve { day, dt, source })?;
        self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
        Ok(x)
    }

    /// Solves by conjugate gradients from the old temperatures.
    fn solve_pcg(
        &mut self,
        b: &[f64],
        t_old: &[f64],
        day: f64,
        dt: f64,
    ) -> Result<Vec<f64>, ThermalError> {
        let sys = &self.sys;
        let t_solve = Instant::now();
        // Start from the old temperatures; prescribed values are exact already.
        let mut x: Vec<f64> = (0..sys.n())
            .map(|i| if sys.fixed[i] { b[i] } else { t_old[i] })
            .collect();
        let max = self.settings.pcg_max_iterations;
        let tolerance = self.settings.pcg_tolerance;
        let iterations = sys
            .solve_pcg(dt, self.settings.theta, b, &mut x, tolerance, max)
            .map_err(|residual| ThermalError::NotConverged {
                day,
                dt,
                iterations: max,
                residual,
            })?;
        self.stats.pcg_iterations += iterations;
        self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
        Ok(x)
    }

    /// Checks the solution `x` against the unmodified equations and returns
    /// the heat gained from the air, from the water and through the fixed
    /// far sides over the step \[J\] (the last two from the reactions of the
    /// fixed rows, split by `far_rows`).
    fn boundary_heat(
        &self,
        rhs: &StepRhs,
        x: &[f64],
        far_rows: &[bool],
        day: f64,
        dt: f64,
    ) -> Result<(f64, f64, f64), ThermalError> {
        let (sys, theta) = (&self.sys, self.settings.theta);
        let n = sys.n();
        // Residual of the unmodified equations on free rows; reactions on fixed rows:
        // r = C T1 + θΔt KH T1 − b_full, where b_full = C T0 − (1−θ)Δt KH T0 + Δt f_θ + Q.
        let mut c_new = vec![0.0; n];
        sys.cap_mul(x, &mut c_new);
        let mut kh_new = vec![0.0; n];
        sys.kh.mul_vec(x, &mut kh_new);
        let (mut res2, mut ref2, mut water_heat, mut far_heat) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let r = c_new[i] + theta * dt * kh_new[i] - rhs.full[i];
            if far_rows[i] {
                far_heat += r;
            } else if sys.fixed[i] {
                water_heat += r;
            } else {
                res2 += r * r;
                ref2 += rhs.full[i] * rhs.full[i] + c_new[i] * c_new[i];
            }
        }
        let residual = (res2 / ref2.max(f64::MIN_POSITIVE)).sqrt();
        if residual > RESIDUAL_TOLERANCE {
            return Err(ThermalError::Residual { day, residual });
        }
        // Air heat = Δt Σ (f_θ − H T_θ); Σ_i (KH T_θ)_i = Σ_i (H T_θ)_i because K
        // annihilates constants (K is symmetric with zero row sums).
        let kh_theta_sum: f64 = (0..n)
            .map(|i| theta * kh_new[i] + (1.0 - theta) * rhs.kh_t[i])
            .sum();
        let air_heat = dt * rhs.ta * sys.air_load.iter().sum::<f64>() - dt * kh_theta_sum;
        Ok((air_heat, water_heat, far_heat))
    }

    /// Ends the stages whose region has fallen to its target by `day`; arms
    /// those whose region is above it.
    fn end_stages_at_target(&mut self, day: f64) {
        for i in 0..self.stages.len() {
            let (StageStatus::Active { armed, .. }, Some(target)) =
                (self.state.status[i].clone(), self.stages[i].target_on(day))
            else {
                continue;
            };
            let mean = self.region_mean(i);
            if armed && mean <= target {
                self.end_stage(i, day, true);
            } else if !armed && mean > target {
                if let StageStatus::Active { armed, .. } = &mut self.state.status[i] {
                    *armed = true;
                }
            }
        }
    }

    /// Stored heat Σ c_i T_i of the live dofs \[J\].
    pub fn stored_heat(&self) -> f64 {
        (0..self.state.live.len())
            .filter(|&e| self.state.live[e])
            .map(|e| self.data.stored_heat(e, &self.state.temperature))
            .sum()
    }

    /// Temperature at a zone point (bilinear on the joint face), if its nodes are live.
    /// `live` is [`ThermalModel::live_dofs`], computed once for all points.
    pub fn point_temperature(&self, mesh: &Mesh, p: &ZoneSite, live: &[bool]) -> Option<f64> {
        let pair = &mesh.face_pairs[p.pair as usize];
        let n = crate::fem::quad4::shape([p.s, p.t]);
        let mut value = 0.0;
        for (k, &node) in pair.nodes_a.iter().enumerate() {
            let d = mesh.thermal_dof[node as usize];
            if !live[d as usize] {
                return None;
            }
            value += n[k] * self.state.temperature[d as usize];
        }
        Some(value)
    }

    /// Temperature of every mesh node (joint duplicates share their dof), NaN where not live.
    pub fn nodal_field(&self, mesh: &Mesh) -> Vec<f64> {
        let mask = self.live_dofs();
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
        self.settings.pipe.is_some()
    }
}

/// Heat released in a step by hydration and pipe cooling.
struct StepSources {
    /// per live dof \[J\]
    q: Vec<f64>,
    /// hydration heat of the step \[J\]
    hydration: f64,
    /// heat the pipes took out (negative) \[J\]
    pipes: f64,
    /// lifts whose source had a running stage
    pipe_terms: usize,
}

/// What the heat balance needs of a step's right-hand side.
struct StepRhs {
    /// air temperature weighted by θ over the step [°C]
    ta: f64,
    /// temperatures at t0, per live dof [°C]
    t_old: Vec<f64>,
    /// KH T0 (zero when θ = 1)
    kh_t: Vec<f64>,
    /// C T0 − (1−θ)Δt KH T0 + Δt f_θ + Q, the prescribed rows included
    full: Vec<f64>,
}

/// Per thermal dof, the fixed temperature of the far side its node is on
/// (`temperatures` in [`crate::mesh::FarSide::ALL`] order); a node on two fixed sides
/// takes the first of them in that order. Empty when no side is fixed, so
/// a scene without `[boundary]` never classifies a face.
fn far_fixed(mesh: &Mesh, temperatures: &[Option<f64>; 5]) -> Vec<Option<f64>> {
    if temperatures.iter().all(Option::is_none) {
        return Vec::new();
    }
    let mut side_of = vec![usize::MAX; mesh.n_thermal_dofs];
    for (f, side) in mesh.far_sides() {
        let side = side.index();
        if temperatures[side].is_none() {
            continue;
        }
        for &k in &crate::fem::hex8::FACES[f.face as usize] {
            let d = mesh.thermal_dof[mesh.elements[f.elem as usize][k] as usize] as usize;
            side_of[d] = side_of[d].min(side);
        }
    }
    side_of
        .into_iter()
        .map(|s| temperatures.get(s).copied().flatten())
        .collect()
}

/// Moves prescribed values to the right-hand side, b_free −= A_{free,fixed}
/// x_fixed with A = C + θΔt KH, and makes the fixed rows read their value.
fn move_prescribed(sys: &LiveSystem, theta_dt: f64, fixed_value: &[f64], b: &mut [f64]) {
    let n = sys.n();
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
            b[i] -= y[i] + theta_dt * ky[i];
        }
    }
}
