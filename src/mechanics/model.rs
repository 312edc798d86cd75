//! The mechanical model of the live elements and its incremental step.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::SVector;
use serde::{Deserialize, Serialize};

use crate::fem::elasticity;
use crate::fem::hex8::FACES;
use crate::fem::{CapacitanceStats, SparseSym};
use crate::material::ageing::ModulusOfAge;
use crate::material::creep::{self, CreepState, StepCoefficients};
use crate::material::Poisson;
use crate::mesh::{Mesh, SurfaceKind, ZoneSite};
use crate::vocab::{JointState, ZoneId};

use super::ahead::{
    AheadStats, Analysed, Assembled, Births, BirthsPlacement, BuildBirths, FactorAhead,
    FactorGuess, NextStep, Order,
};
use super::contact_step::{self, PassRecord, Prepared, RefactorCounts, StepSystem};
use super::error::MechError;
use super::error::RESIDUAL_TOLERANCE;
use super::frame::Frame;
use super::grout_stops::StopSample;
use super::joints::{Grout, JointPoint, JointPointState, PointState};
use super::live::{LiveError, LiveSystem, NONE, PARALLEL_FROM_DOFS};
use super::pours_ahead::{PoursAhead, PoursAheadStats, Taken};
use super::settings::MechanicsSettings;

/// Gravity [m/s²].
pub const GRAVITY: f64 = 9.81;
/// Water density [kg/m³].
pub const WATER_DENSITY: f64 = 1000.0;
/// Prescribed zero displacement increments: (node, component 0..3).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Supports {
    pub fixed: Vec<(u32, u8)>,
}

impl Supports {
    /// Per node dof (3 per node of `n_nodes`): is it fixed?
    pub fn flags(&self, n_nodes: usize) -> Vec<bool> {
        let mut supported = vec![false; 3 * n_nodes];
        for &(node, comp) in &self.fixed {
            supported[3 * node as usize + comp as usize] = true;
        }
        supported
    }

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

/// The thermal-dof temperatures a mechanical step reads: at its start
/// (after that day's pours), at each midnight inside it with the day's time
/// (a step spanning several days; none for a step of a day), and at its end.
#[derive(Debug, Clone, Copy)]
pub struct StepTemperatures<'a> {
    pub start: &'a [f64],
    pub inside: &'a [(f64, Vec<f64>)],
    pub end: &'a [f64],
}

/// The joint read at one site: what a joint meter and a pressure cell
/// set there would show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointReading {
    /// aperture \[m\]
    pub aperture: f64,
    pub state: JointState,
    /// pressure across the joint \[Pa\], compression positive: the contact
    /// pressure of a closed joint, the grout layer's (negative in tension)
    /// once grouted, 0 where open. The joint points' normal forces over
    /// their tributary areas ([`MechanicsModel::joint_pressure`]),
    /// interpolated like the aperture.
    pub pressure: f64,
}

/// A zone's smallest aperture inside its grout stops
/// ([`MechanicsModel::zone_min_aperture`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoneMinimum {
    pub reading: JointReading,
    /// the side-a nodes the aperture is interpolated between, with their
    /// weights (the second weight is 0 at a node): the temperature there is
    /// read with the same weights
    pub nodes: [(u32, f64); 2],
}

/// Counters for the benchmark.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MechStats {
    /// steps taken
    pub steps: usize,
    /// live-set rebuilds (numbering + symbolic factorisation)
    pub symbolic: usize,
    /// numeric factorisations, the contact solves' included
    pub numeric: usize,
    /// largest live system \[dofs\], supported ones included
    pub max_dofs: usize,
    /// largest number of free (not supported) dofs of a live system
    #[serde(default)]
    pub max_free_dofs: usize,
    /// wall time of the rebuilds \[s\] (orderings included)
    pub seconds_symbolic: f64,
    /// METIS calls: one per live set with `solver.ordering = "metis_live_set"`,
    /// one for the whole construction with `"metis"`
    #[serde(default)]
    pub metis_calls: usize,
    /// wall time of the elimination orders (METIS, restrictions) \[s\]
    #[serde(default)]
    pub seconds_ordering: f64,
    /// wall time of faer's symbolic analyses in those orders \[s\]
    #[serde(default)]
    pub seconds_analysis: f64,
    /// Σ over the live sets of the entries of L
    #[serde(default)]
    pub live_sets_factor_nnz: u64,
    /// Σ over the live sets of the flops of one factorisation
    #[serde(default)]
    pub live_sets_factor_flops: f64,
    /// Σ over the numeric factorisations of their flops (the work done)
    #[serde(default)]
    pub numeric_flops: f64,
    /// wall time of the numeric factorisations \[s\]
    pub seconds_numeric: f64,
    /// wall time of the solves without joints \[s\]
    pub seconds_solve: f64,
    /// wall time of the assembly \[s\]
    pub seconds_assembly: f64,
    /// contact solves of the joints
    pub seconds_joints: f64,
    /// contact iterations (active-set passes or cone-program solves)
    pub contact_iterations: usize,
    /// of the active-set passes, those that moved only slip forces (the
    /// fixed point of the slipping points not solved with the states)
    #[serde(default)]
    pub slip_force_passes: usize,
    /// largest tension \[Pa\] left on a joint point kept closed by the flip limit
    pub kept_closed_tension: f64,
    /// steps whose normal contact states switched by block pivoting
    /// (frictional points cycling; `contact_step::BlockPivoting`)
    #[serde(default)]
    pub block_pivoting_steps: usize,
    /// why the joint solves factorised
    #[serde(default)]
    pub refactor_reasons: RefactorCounts,
    /// the capacitance corrections that replaced factorisations (their
    /// time is part of `seconds_joints`)
    #[serde(default)]
    pub capacitance: CapacitanceStats,
    /// the next steps' factorisations made on the second core
    /// ([`super::ahead`]; also counted in `numeric`, their time not in
    /// `seconds_numeric`)
    #[serde(default)]
    pub ahead: AheadStats,
    /// the coming pour days' live systems analysed on threads of their own
    /// ([`super::pours_ahead`]; their analyses also counted in `symbolic`
    /// when a step takes them, their time not in `seconds_symbolic`)
    #[serde(default)]
    pub pours_ahead: PoursAheadStats,
    /// unknowns of the rock condensed once per run
    /// ([`super::rock_condensation`]; not counted in `max_dofs`)
    #[serde(default)]
    pub condensed_dofs: usize,
    /// wall time of that condensation \[s\]
    #[serde(default)]
    pub seconds_condensation: f64,
    /// solves with the condensed rock's factor (a step's loads condensed
    /// when the rock is loaded, its x_R recovered)
    #[serde(default)]
    pub rock_solves: usize,
    /// wall time of the steps' condensing and recovering \[s\]
    #[serde(default)]
    pub seconds_rock: f64,
    /// most nodes layer merging tied in a live system
    /// ([`super::layer_merging`]; 0 when it is off)
    #[serde(default)]
    pub max_merged_nodes: usize,
}

impl MechStats {
    /// Counts `n` numeric factorisations of `flops_each` flops that took
    /// `seconds` on this thread (0 for those made ahead on the other core).
    fn count_numeric(&mut self, n: usize, flops_each: f64, seconds: f64) {
        self.numeric += n;
        self.numeric_flops += n as f64 * flops_each;
        self.seconds_numeric += seconds;
    }

    /// Counts the analysis of the live system `sys`.
    fn count_live(&mut self, sys: &LiveSystem) {
        self.symbolic += 1;
        self.metis_calls += sys.ordering.metis_calls;
        self.seconds_ordering += sys.ordering.seconds;
        self.seconds_analysis += sys.solver.stats().symbolic_seconds;
        self.live_sets_factor_nnz += sys.solver.factor_nnz() as u64;
        self.live_sets_factor_flops += sys.solver.factor_flops();
        self.max_dofs = self.max_dofs.max(sys.n_all());
        let free = sys.supported.iter().filter(|&&s| !s).count();
        self.max_free_dofs = self.max_free_dofs.max(free);
    }

    /// A warning line when a contact step ended with joint points held
    /// closed in tension at the flip limit (`contact_step::MAX_FLIPS`): the
    /// apertures beside them are not an equilibrium answer. Empty otherwise.
    pub fn kept_tension_warning(&self) -> String {
        if self.kept_closed_tension > 0.0 {
            format!(
                "warning: a contact step kept joint points closed in tension up to {:.3} MPa (their open/closed state cycled to the flip limit); the apertures beside them are not an equilibrium answer\n",
                self.kept_closed_tension / 1e6
            )
        } else {
            String::new()
        }
    }
}

/// Checkpointable mechanical state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MechState {
    /// displacement accumulated since each node's birth, 3 per node \[m\]
    pub u: Vec<f64>,
    /// per element: born (poured, or rock)
    pub live: Vec<bool>,
    /// per element: day it was born (NaN before)
    pub birth_day: Vec<f64>,
    /// per element and Gauss point \[Pa\]
    pub stress: Vec<[[f64; 6]; 8]>,
    /// per element × 8 Gauss points when creep is on
    pub creep: Vec<CreepState>,
    /// external load accumulated so far, per dof \[N\]
    pub f_ext: Vec<f64>,
    /// water load applied so far, per dof \[N\]
    pub water_load: Vec<f64>,
    /// per element: its weight is in `f_ext` (the rock's never strains it)
    pub weight_applied: Vec<bool>,
    /// one per joint contact point (empty without the `joints` effect)
    pub joints: Vec<JointPointState>,
    /// nodal forces of the joint contacts, per dof \[N\] (total, not incremental)
    pub f_contact: Vec<f64>,
    /// what the factor made ahead for the next step was guessed from, if
    /// one was made: a run restarted here factorises its first step from
    /// it ([`super::ahead`])
    #[serde(default)]
    pub next_factor_guess: Option<FactorGuess>,
}

/// The staged mechanical model.
pub struct MechanicsModel {
    /// what a run never changes, shared with the thread working ahead and
    /// with other runs of the scene ([`MechanicsModel::on_frame`])
    frame: Arc<Frame>,
    /// displacement increments of supported dofs for the next step (global dof, value)
    prescribed: Vec<(u32, f64)>,
    /// the system of the live set at the last rebuild (empty before the first step)
    sys: LiveSystem,
    /// the live set has changed since `sys` was built
    dirty: bool,
    pub state: MechState,
    pub stats: MechStats,
    /// the next step's factorisation, made while this one runs
    ahead: FactorAhead,
    /// the coming pour day's live system, analysed ahead
    pours_ahead: PoursAhead,
    /// a restored state's [`MechState::next_factor_guess`], for the first
    /// step after the restore
    restored_guess: Option<FactorGuess>,
    /// the nodes layer merging ties in the live system (sorted)
    merged: Vec<u32>,
    /// the contact passes of the last step with joint pairs
    joint_passes: Vec<PassRecord>,
}

impl MechState {
    /// The state before the first pour: only the rock lives, born
    /// stress-free at day 0.
    fn before_pours(
        n_nodes: usize,
        concrete: &[bool],
        n_points: usize,
        n_creep: usize,
    ) -> MechState {
        let n_el = concrete.len();
        let mut state = MechState {
            joints: vec![JointPointState::UNPAIRED; n_points],
            f_contact: vec![0.0; 3 * n_nodes],
            u: vec![0.0; 3 * n_nodes],
            live: vec![false; n_el],
            birth_day: vec![f64::NAN; n_el],
            stress: vec![[[0.0; 6]; 8]; n_el],
            // The rock never creeps: its points keep no terms (on the
            // Xiaowan-like arch half the elements, a third of a checkpoint).
            creep: if n_creep > 0 {
                concrete
                    .iter()
                    .flat_map(|&c| {
                        std::iter::repeat_n(CreepState::new(if c { n_creep } else { 0 }), 8)
                    })
                    .collect()
            } else {
                Vec::new()
            },
            f_ext: vec![0.0; 3 * n_nodes],
            water_load: vec![0.0; 3 * n_nodes],
            weight_applied: vec![false; n_el],
            next_factor_guess: None,
        };
        for e in (0..n_el).filter(|&e| !concrete[e]) {
            state.live[e] = true;
            state.birth_day[e] = 0.0;
            // The foundation's own weight is in equilibrium with the ground
            // before construction: it does not strain the rock.
            state.weight_applied[e] = true;
        }
        state
    }
}

/// The step's linear system before supports, contact and external loads,
/// and what its commit needs per live element.
struct StepAssembly {
    a: SparseSym,
    b: Vec<f64>,
    /// creep recursion coefficients, per element slot of the live system
    coeffs: Vec<StepCoefficients>,
    /// strain increments imposed at constant stress, per slot and Gauss point
    pseudo: Vec<[[f64; 6]; 8]>,
    /// with the incompatible modes, the modes' share f̂_α of those strains'
    /// load at E = 1, per slot (zero where nothing is imposed; empty with
    /// the plain hex8): the load's condensation and the amplitudes' recovery
    /// at the commit both need it
    mode_loads: Vec<SVector<f64, 9>>,
}

impl MechanicsModel {
    /// The node and component (0, 1, 2 = x, y, z) of an unknown of the
    /// current live system, if it is a node's (not a joint pair's).
    pub fn node_of_unknown(&self, dof: usize) -> Option<(u32, u8)> {
        self.sys
            .node_dofs
            .iter()
            .find(|&&(_, r)| r as usize == dof)
            .map(|&(g, _)| (g / 3, (g % 3) as u8))
    }

    /// The contact points of the joints (the `joints` effect).
    pub fn points(&self) -> &[JointPoint] {
        &self.frame.points
    }

    /// Builds the model; rock elements are born (stress-free) at day 0.
    pub fn new(
        mesh: &Mesh,
        settings: &MechanicsSettings,
        supports: &Supports,
    ) -> Result<MechanicsModel, MechError> {
        let supported = supports.flags(mesh.nodes.len());
        let (frame, costs) = Frame::build(mesh, settings, supported)?;
        let mut model = MechanicsModel::on_frame(Arc::new(frame))?;
        model.stats.metis_calls = costs.metis_calls;
        model.stats.seconds_ordering = costs.seconds_ordering;
        model.stats.seconds_condensation = costs.seconds_condensation;
        Ok(model)
    }

    /// A model before its first pour on `frame`, the frame of another
    /// model of the same scene and mesh ([`MechanicsModel::frame`]): what
    /// [`MechanicsModel::new`] builds, without making the frame again (the
    /// construction ordering's METIS call on the complete dam and the rock
    /// condensation). Its stats count neither; the condensed rock is still
    /// reported.
    pub fn on_frame(frame: Arc<Frame>) -> Result<MechanicsModel, MechError> {
        let state = MechState::before_pours(
            frame.n_nodes,
            &frame.tables.concrete,
            frame.points.len(),
            frame.creep_terms(),
        );
        let sys = LiveSystem::empty(&frame.points, frame.n_nodes)
            .map_err(|source| MechError::Live { day: 0.0, source })?;
        Ok(MechanicsModel {
            prescribed: Vec::new(),
            sys,
            dirty: true,
            state,
            stats: MechStats {
                condensed_dofs: frame.rock.as_ref().map_or(0, |r| r.n()),
                ..MechStats::default()
            },
            ahead: FactorAhead::new(factor_ahead(&frame.settings)),
            pours_ahead: PoursAhead::new(factor_ahead(&frame.settings)),
            restored_guess: None,
            merged: Vec::new(),
            joint_passes: Vec::new(),
            frame,
        })
    }

    /// This model's frame, for [`MechanicsModel::on_frame`].
    pub fn frame(&self) -> Arc<Frame> {
        Arc::clone(&self.frame)
    }

    /// Restores a checkpointed state ([`MechanicsModel::state`] of a run of
    /// the same scene); the live system is renumbered and refactorised on the
    /// next step, as after a pour.
    pub fn restore(&mut self, state: &MechState) {
        self.settle_ahead();
        self.state = state.clone();
        self.prescribed.clear();
        self.dirty = true;
        self.ahead.forget();
        self.restored_guess = self.state.next_factor_guess.clone();
    }

    /// Factorise the next step on the second core while a step's contact
    /// passes run (`solver.factor_ahead`; [`super::ahead`]). Off where the
    /// cores are otherwise busy; the answer is the same to round-off.
    pub fn set_factor_ahead(&mut self, on: bool) {
        self.settle_ahead();
        self.ahead
            .set_enabled(on && factor_ahead(&self.frame.settings));
        self.set_pours_ahead(on);
    }

    /// Analyse the coming pour days' live systems ahead, on threads of their
    /// own (on with [`MechanicsModel::set_factor_ahead`];
    /// [`super::pours_ahead`]). The answer is the same to the bit.
    pub fn set_pours_ahead(&mut self, on: bool) {
        self.pours_ahead
            .set_enabled(on && factor_ahead(&self.frame.settings));
    }

    /// Where the next live set is analysed when the next step pours lifts
    /// (balanced between the cores by default; the answer is the same).
    pub fn set_births_placement(&mut self, placement: BirthsPlacement) {
        self.ahead.set_births_placement(placement);
    }

    /// Waits for the factorisation running ahead, if any, and counts it.
    fn settle_ahead(&mut self) {
        if let Some(flops) = self.ahead.settle() {
            self.stats.count_numeric(1, flops, 0.0);
            if let Some(sys) = self.ahead.born() {
                self.stats.count_live(sys);
            }
        }
        self.stats.ahead = self.ahead.stats;
    }

    /// The step after the next [`MechanicsModel::step`], when no grouting
    /// at its start changes the system (the driver knows; None otherwise):
    /// its factorisation may then be made while the next step runs.
    pub fn set_next_step(&mut self, next: Option<NextStep>) {
        self.ahead.set_next(next);
    }

    /// Pours lift `lift` of `block` on `day`: its elements are born stress-free.
    pub fn pour(&mut self, block: u32, lift: u32, day: f64) {
        let state = &mut self.state;
        if self
            .frame
            .pour(&[(block, lift)], day, &mut state.live, &mut state.birth_day)
        {
            self.dirty = true;
        }
    }

    /// Numbers the live unknowns (nodes and joint pairs) and analyses the
    /// pattern, or adopts the live system made ahead for these elements;
    /// pairs whose second node has just been born start open with the
    /// scene's initial gap.
    fn rebuild(&mut self, merged: Vec<u32>) -> Result<(), LiveError> {
        let pair_live = self.pair_live(&self.state.live);
        for (p, st) in self.newly_paired(&pair_live) {
            self.state.joints[p] = st;
        }
        self.sys = match self.ahead.adopt(&self.state.live, &merged) {
            Some(sys) => sys,
            None => match self.analysed_ahead(&merged) {
                Some(sys) => sys,
                None => {
                    let live = self.state.live.clone();
                    self.build_live(&live, &pair_live, &merged)?
                }
            },
        };
        self.stats.max_merged_nodes = self.stats.max_merged_nodes.max(merged.len());
        self.merged = merged;
        self.dirty = false;
        Ok(())
    }

    /// Whether each joint point is live (both its nodes in a live element)
    /// when the elements `live` are.
    fn pair_live(&self, live: &[bool]) -> Vec<bool> {
        let mut node_live = vec![false; self.frame.node_xyz.len()];
        for (e, conn) in self.frame.elements.iter().enumerate() {
            if live[e] {
                conn.iter().for_each(|&k| node_live[k as usize] = true);
            }
        }
        self.frame
            .points
            .iter()
            .map(|p| node_live[p.a as usize] && node_live[p.b as usize])
            .collect()
    }

    /// The points `pair_live` pairs that are not paired yet, with the state
    /// each starts in.
    fn newly_paired(&self, pair_live: &[bool]) -> Vec<(usize, JointPointState)> {
        // A block cast against its neighbour starts touching it: the first
        // guess is closed (most new pairs are pressed by the fresh
        // concrete's weight and expansion), open with a gap.
        let gap = self.frame.settings.joint.initial_gap_m;
        let closed = gap == 0.0 && self.frame.joint_settings.mu_static > 0.0;
        let start = JointPointState {
            paired: true,
            gap,
            state: if closed {
                PointState::Stick
            } else {
                PointState::Open
            },
            ..JointPointState::UNPAIRED
        };
        pair_live
            .iter()
            .enumerate()
            .filter(|&(p, &on)| on && !self.state.joints[p].paired)
            .map(|(p, _)| (p, start))
            .collect()
    }

    /// The live system of today's elements and `merged` tied nodes, when it
    /// was analysed ahead ([`super::pours_ahead`]), counted; the wait for
    /// it is counted as an analysis on this thread.
    fn analysed_ahead(&mut self, merged: &[u32]) -> Option<LiveSystem> {
        let t = Instant::now();
        let sys = self.pours_ahead.take(&self.state.live, merged)?.join()?;
        self.stats.count_live(&sys);
        self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
        Some(sys)
    }

    /// Starts analysing the live system of the first pour day after this
    /// step that no order of this step analyses ([`super::pours_ahead`]):
    /// the next step's, unless its factor made ahead analyses it
    /// (`births_ordered`), then the following pour day's.
    ///
    /// Not where the live system factorises on both cores (as for the
    /// factor made ahead): on the Xiaowan-like arch's days 856–862 the
    /// analyses ahead took 1.9 s off the steps' 100 s and added 0.7 GB to
    /// their peak (5.8 against 5.1 GB), which its 8 GB budget cannot spare.
    fn analyse_pours_ahead(&mut self, next: Option<&NextStep>, births_ordered: bool) {
        let small = self.sys.n < PARALLEL_FROM_DOFS;
        let Some(next) = next.filter(|_| small && self.pours_ahead.enabled()) else {
            return;
        };
        let mut live = self.state.live.clone();
        let mut birth = self.state.birth_day.clone();
        let t1 = next.interval.0;
        for (day, lifts) in &next.pours {
            self.frame.pour(lifts, *day, &mut live, &mut birth);
        }
        let day = if next.pours.is_empty() || births_ordered {
            let Some((start, pours)) = &next.later_pours else {
                return;
            };
            for (day, lifts) in pours {
                self.frame.pour(lifts, *day, &mut live, &mut birth);
            }
            *start
        } else {
            t1
        };
        if live == self.state.live {
            return;
        }
        let merged = self.frame.merge.tied_at(&live, &birth, day);
        if self.pours_ahead.holds(&live, &merged) {
            return;
        }
        let pair_live = self.pair_live(&live);
        let frame = Arc::clone(&self.frame);
        self.pours_ahead
            .start(live.clone(), merged.clone(), move || {
                frame.live_system(&live, &pair_live, &merged)
            });
    }

    /// Numbers and analyses the live system of the elements `live`, counted.
    fn build_live(
        &mut self,
        live: &[bool],
        pair_live: &[bool],
        merged: &[u32],
    ) -> Result<LiveSystem, LiveError> {
        let t = Instant::now();
        let sys = self.frame.live_system(live, pair_live, merged)?;
        self.stats.count_live(&sys);
        self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
        Ok(sys)
    }

    /// Prescribes the displacement increment of a supported dof for the next
    /// step (a jack, a settlement; the supports are otherwise fixed).
    pub fn prescribe(&mut self, node: u32, comp: u8, increment: f64) -> Result<(), MechError> {
        let g = 3 * node as usize + comp as usize;
        if comp > 2 || !self.frame.supported.get(g).copied().unwrap_or(false) {
            return Err(MechError::NotSupported { node, comp });
        }
        self.prescribed.push((g as u32, increment));
        Ok(())
    }

    /// Grouts zone `zone` of joint `joint` on `day`: each of its live points
    /// becomes a grout layer (eqs. 28–29 of the seed paper) whose reference is
    /// the present deformed geometry, whose thickness is the present aperture
    /// (at least the scene's floor) and which keeps the present contact force.
    /// Returns the number of points grouted.
    pub fn grout(&mut self, joint: u32, zone: u32, day: f64) -> usize {
        let j = &self.frame.settings.joint;
        let moduli = [
            j.grout_shear_modulus_pa,
            j.grout_shear_modulus_pa,
            j.grout_modulus_pa,
        ];
        let id = ZoneId::new(joint, zone);
        let mut n = 0;
        for (p, pt) in self.frame.points.iter().enumerate() {
            let st = &mut self.state.joints[p];
            if !takes_grout(pt, st, id) {
                continue;
            }
            let aperture = st.gap.max(0.0);
            let thickness = aperture.max(j.grout_min_thickness_m);
            st.grout = Some(Grout {
                day,
                aperture,
                thickness,
                stiffness: moduli.map(|d| pt.area * d / thickness),
                cracked_day: None,
            });
            st.gap = 0.0;
            st.state = PointState::Grouted;
            n += 1;
        }
        n
    }

    /// The guess of a factor made ahead ([`super::ahead`]) for a step whose
    /// start grouts zones: `states` with those zones' points open. The
    /// step then holds none of their rows and adds their layers' springs
    /// to the diagonal, a change the capacitance correction takes (rows
    /// stiffened: its matrix stays well conditioned). Guessed grouted,
    /// with springs from the gaps a day early, the correction would take
    /// the day's change of each spring, near-cancelling terms of the
    /// size of the springs (a residual of 6.6e-6 on the demo's first
    /// grouting day, against the 1e-8 a pass needs).
    fn grouting_guess(&self, states: &[JointPointState], next: &NextStep) -> Vec<JointPointState> {
        let mut guess = states.to_vec();
        for &z in &next.grouting {
            for (pt, st) in self.frame.points.iter().zip(guess.iter_mut()) {
                if takes_grout(pt, st, z) {
                    st.state = PointState::Open;
                }
            }
        }
        guess
    }

    /// Temperature at each Gauss point of element `e` from thermal-dof
    /// temperatures, before and after the step.
    fn gauss_temperatures(&self, e: usize, before: &[f64], after: &[f64]) -> [[f64; 8]; 2] {
        let dofs = self.frame.elements[e].map(|v| self.frame.thermal_dof[v as usize] as usize);
        let n = crate::fem::hex8::shape_at_gauss2();
        [before, after]
            .map(|temps| std::array::from_fn(|g| (0..8).map(|k| n[g][k] * temps[dofs[k]]).sum()))
    }

    /// Hydrostatic load of the water at `level` on the live wet faces, per dof.
    fn water_load(&self, level: Option<f64>) -> Result<Vec<f64>, MechError> {
        let mut f = vec![0.0; self.state.u.len()];
        let Some(level) = level.filter(|_| self.frame.settings.reservoir_load) else {
            return Ok(f);
        };
        for &(e, face) in &self.frame.wet_faces {
            if !self.state.live[e as usize] {
                continue;
            }
            let ids = FACES[face as usize];
            let fc: [[f64; 3]; 4] = std::array::from_fn(|k| {
                self.frame.node_xyz[self.frame.elements[e as usize][ids[k]] as usize]
            });
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
                let node = self.frame.elements[e as usize][ids[k]] as usize;
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
        let temps = temps.map(|(start, end)| StepTemperatures {
            start,
            inside: &[],
            end,
        });
        self.step_through(t0, t1, temps, water_level)
    }

    /// [`MechanicsModel::step`] over a step that may span several days, with
    /// the temperatures at the midnights inside it as well: each day's change
    /// of temperature then strains the concrete at that day's modulus
    /// ([`MechanicsModel::day_weighted_strains`]).
    pub fn step_through(
        &mut self,
        t0: f64,
        t1: f64,
        temps: Option<StepTemperatures<'_>>,
        water_level: Option<f64>,
    ) -> Result<(), MechError> {
        // layer merging ties more nodes from today: a new live system
        let merged = self
            .frame
            .merge
            .tied_at(&self.state.live, &self.state.birth_day, t0);
        if merged != self.merged {
            self.dirty = true;
        }
        let upcoming = self.ahead.next_step().cloned();
        // The next step's factorisation is ordered and started before this
        // step waits for its own (still being made on the other core), so
        // that a core never waits for an order: it idled 21.8 s of the
        // demo's 78.6 s between a factor and the next when the order was
        // made after the wait (28 Nov 2026), and 6.8 s of 52.3 s when the
        // order was made before the wait but started after it (30 Nov). A
        // rebuild pending orders it after the rebuild, on the new live
        // system.
        let early = !(self.dirty || self.sys.pairs.is_empty());
        if early {
            self.state.next_factor_guess = None;
            let order = self.order_next();
            self.start_next(order, upcoming.as_ref());
        }
        // what was made ahead is this step's (or discarded by it)
        self.settle_ahead();
        if self.dirty {
            self.rebuild(merged)
                .map_err(|source| MechError::Live { day: t1, source })?;
        }
        let t_asm = Instant::now();
        let k = self.step_stiffness(t0, t1)?;
        self.stats.seconds_assembly += t_asm.elapsed().as_secs_f64();
        // this step's factor taken (and the next one's started, when not
        // early) before the loads are assembled
        let prepared = if self.sys.pairs.is_empty() {
            self.analyse_pours_ahead(upcoming.as_ref(), false);
            None
        } else {
            self.take_factor_start_next(t0, t1, &k.stiffness, early, upcoming.as_ref())?
        };
        let t_asm = Instant::now();
        let StepAssembly {
            a,
            mut b,
            coeffs,
            pseudo,
            mode_loads,
        } = self.assemble(k, temps.map(|temps| (t0, temps, t1)));
        let (df_ext, water) = self.external_loads(water_level)?;
        let ext = self.sys.reduce(&df_ext, &self.frame.points);
        for (b, e) in b.iter_mut().zip(&ext) {
            *b += e;
        }
        let Prescribed {
            system: prescribed,
            condensed: held,
        } = self.take_prescribed()?;
        self.stats.seconds_assembly += t_asm.elapsed().as_secs_f64();
        let (b, condensed) = self.condense(b, &held, t1)?;

        let x = if self.sys.pairs.is_empty() {
            self.solve_plain(a, b, &prescribed, t1)?
        } else {
            self.solve_joints(&a, &b, &prescribed, t1, prepared)?
        };
        let x = self.recover(x, condensed, t1)?;

        self.commit(&x, &coeffs, &pseudo, &mode_loads, &df_ext, water);
        self.stats.steps += 1;
        self.stats.ahead = self.ahead.stats;
        self.stats.pours_ahead = self.pours_ahead.stats();
        Ok(())
    }

    /// This step's factor made ahead, if any (after a restore: made now
    /// from the guess the checkpoint carries; None: the step factorises),
    /// and, unless it was started `early` (before this step waited for its
    /// factor), the next step's factorisation started now from this step's
    /// start states, when due ([`super::ahead`]); `upcoming` is the next
    /// step as the driver named it.
    fn take_factor_start_next(
        &mut self,
        t0: f64,
        t1: f64,
        a: &SparseSym,
        early: bool,
        upcoming: Option<&NextStep>,
    ) -> Result<Option<Prepared>, MechError> {
        let prepared = match self.ahead.take(t0, t1, &mut self.sys, a) {
            Some(p) => Some(p),
            None => self.factor_restored_guess(a, t0, t1)?,
        };
        if !early {
            self.state.next_factor_guess = None;
            let order = self.order_next();
            self.start_next(order, upcoming);
        }
        Ok(prepared)
    }

    /// Starts the factorisation of `order` on a thread of its own, and the
    /// analysis of the first pour day's live system after it that the
    /// order does not analyse, from `upcoming` ([`super::pours_ahead`]).
    fn start_next(&mut self, order: Option<Order>, upcoming: Option<&NextStep>) {
        self.analyse_pours_ahead(upcoming, order.as_ref().is_some_and(Order::pours));
        match order.map(|o| self.ahead.job(o, &self.sys)) {
            Some(Ok(job)) => {
                // the guess is the checkpoint's from now: a restarted run
                // factorises the next step from it as this job does
                self.state.next_factor_guess = Some(job.guess());
                self.ahead.start(job);
            }
            Some(Err(_)) => self.ahead.not_made(),
            None => {}
        }
    }

    /// The next step's order when its factorisation is due: its K̃ on this
    /// live system, or on the next live system analysed now when its start
    /// pours lifts, and its first pass guessed from the states now. Its
    /// assembly is counted as assembly, the next live set's analysis as
    /// symbolic; an error of the next step's system is the next step's to
    /// report.
    fn order_next(&mut self) -> Option<Order> {
        let next = self.ahead.due(&self.sys)?;
        let t_asm = Instant::now();
        let symbolic_before = self.stats.seconds_symbolic;
        let (t0, t1) = next.interval;
        let same_merged = next.pours.is_empty()
            && self
                .frame
                .merge
                .tied_at(&self.state.live, &self.state.birth_day, t0)
                == self.merged;
        let order = if same_merged {
            let (sys, birth) = (&self.sys, &self.state.birth_day);
            let guess = self.grouting_guess(&self.state.joints, &next);
            self.frame
                .stiffness(sys, birth, t0, t1)
                .ok()
                .map(|k| Order::new(next.interval, k, sys, &guess))
        } else {
            self.births(&next)
        };
        let symbolic = self.stats.seconds_symbolic - symbolic_before;
        self.stats.seconds_assembly += t_asm.elapsed().as_secs_f64() - symbolic;
        order
    }

    /// The order of the next step, whose start pours `next.pours`: its live
    /// system, K̃ and first pass's matrix, from this step's start states and
    /// the new pairs as a rebuild starts them. They are made on a thread of
    /// their own from now, unless the last step waited for its factor made
    /// ahead: then the other core is the busier one, and they are made here
    /// (the answer is the same either way). Measured alone on the 2 cores
    /// (28 Nov 2026): the demo's whole construction 59.1–61.3 s always on a
    /// thread, 61.2–61.8 s always here, 59.2–60.9 s with this rule; the
    /// Xiaowan-like first 120 days (where the other core factorises 1.6 s
    /// a step beside the step's 1.3 s) 174.7, 159.8 and 159.4 s. None when
    /// the pours add no element.
    fn births(&mut self, next: &NextStep) -> Option<Order> {
        let (t0, t1) = next.interval;
        let mut live = self.state.live.clone();
        let mut birth = self.state.birth_day.clone();
        for (day, lifts) in &next.pours {
            self.frame.pour(lifts, *day, &mut live, &mut birth);
        }
        let merged = self.frame.merge.tied_at(&live, &birth, t0);
        if live == self.state.live && merged == self.merged {
            return None;
        }
        let pair_live = self.pair_live(&live);
        let paired = self.newly_paired(&pair_live);
        // the step grouts before it pours (`Simulation::apply_mechanics_events`)
        let mut states = self.grouting_guess(&self.state.joints, next);
        for &(p, st) in &paired {
            states[p] = st;
        }
        let frame = Arc::clone(&self.frame);
        let guess = states.clone();
        let analysed = self.pours_ahead.take(&live, &merged);
        let work = move || {
            let sys = match analysed.and_then(Taken::join) {
                Some(sys) => sys,
                None => frame.live_system(&live, &pair_live, &merged).ok()?,
            };
            let assembled = frame.stiffness(&sys, &birth, t0, t1).ok()?;
            let prepared = Prepared::first_pass(&assembled.stiffness, &sys, &guess);
            Some(Analysed {
                births: Births {
                    live,
                    merged,
                    paired,
                    sys,
                },
                assembled,
                prepared,
                seconds: 0.0,
            })
        };
        let build: BuildBirths = if self.ahead.births_here() {
            let t = Instant::now();
            let done = work();
            // counted as an analysis on this thread, like a rebuild's
            self.stats.seconds_symbolic += t.elapsed().as_secs_f64();
            Box::new(move || done)
        } else {
            let h = std::thread::spawn(move || {
                let t = Instant::now();
                let mut done = work();
                if let Some(a) = done.as_mut() {
                    a.seconds = t.elapsed().as_secs_f64();
                }
                done
            });
            Box::new(move || h.join().ok().flatten())
        };
        Some(Order::births(next.interval, states, build))
    }

    /// After a restore, the first step's factor as the run that wrote the
    /// checkpoint made it ahead: from the guess it carries, when that was
    /// for this step (None otherwise, or past the first step).
    fn factor_restored_guess(
        &mut self,
        a: &SparseSym,
        t0: f64,
        t1: f64,
    ) -> Result<Option<Prepared>, MechError> {
        let Some(guess) = self.restored_guess.take() else {
            return Ok(None);
        };
        if guess.interval != (t0, t1) || guess.states.len() != self.state.joints.len() {
            return Ok(None);
        }
        let prepared = Prepared::first_pass(a, &self.sys, &guess.states);
        let t = Instant::now();
        self.sys
            .solver
            .factorize(&prepared.m)
            .map_err(|source| MechError::Solve { day: t1, source })?;
        let flops = self.sys.solver.factor_flops();
        self.stats
            .count_numeric(1, flops, t.elapsed().as_secs_f64());
        Ok(Some(prepared))
    }

    /// The stiffness of the live elements at their mid-step ages and their
    /// coefficients (made ahead when they were: [`FactorAhead::assembled`]).
    fn step_stiffness(&mut self, t0: f64, t1: f64) -> Result<Assembled, MechError> {
        let (sys, birth) = (&self.sys, &self.state.birth_day);
        match self.ahead.assembled(t0, t1, sys, birth) {
            Some(made) => Ok(made),
            None => self.frame.stiffness(sys, birth, t0, t1),
        }
    }

    /// The step's system of stiffness `k`: the loads of the strains it
    /// imposes.
    fn assemble(&self, k: Assembled, temps: Option<(f64, StepTemperatures, f64)>) -> StepAssembly {
        let sys = &self.sys;
        let Assembled {
            stiffness: a,
            coeffs,
            ..
        } = k;
        let mut b = vec![0.0; sys.n_all()];
        let mut pseudo: Vec<[[f64; 6]; 8]> = Vec::with_capacity(sys.elements.len());
        let mut mode_loads = Vec::new();
        for (slot, el) in sys.elements.iter().enumerate() {
            let e = el.elem as usize;
            let c = &coeffs[slot];
            let eps = self.imposed_strain(e, c, temps);
            let imposed = eps.iter().any(|g| g.iter().any(|&v| v != 0.0));
            let modes = self.frame.tables.modes.get(e);
            let f_alpha = match modes {
                Some(m) if imposed => {
                    let q = elasticity::poisson_matrix(self.frame.tables.nu[e]);
                    m.mode_load(&self.frame.tables.gauss[e], &q, &eps)
                }
                _ => SVector::zeros(),
            };
            if imposed {
                let d = elasticity::isotropic_d(c.e_eff, self.frame.tables.nu[e]);
                let mut load =
                    elasticity::initial_strain_load(&self.frame.tables.gauss[e], &d, &eps);
                if let Some(m) = modes {
                    load = m.condense_load(&load, &(f_alpha * c.e_eff));
                }
                sys.add_element_vector(slot, &load, &self.frame.points, &mut b);
            }
            if modes.is_some() {
                mode_loads.push(f_alpha);
            }
            pseudo.push(eps);
        }
        StepAssembly {
            a,
            b,
            coeffs,
            pseudo,
            mode_loads,
        }
    }

    /// Strains the step imposes on element `e` at constant stress, per Gauss
    /// point: creep, thermal, autogenous.
    fn imposed_strain(
        &self,
        e: usize,
        c: &StepCoefficients,
        temps: Option<(f64, StepTemperatures, f64)>,
    ) -> [[f64; 6]; 8] {
        let mut eps = [[0.0; 6]; 8];
        if !self.state.creep.is_empty() && self.frame.tables.concrete[e] {
            for (g, eg) in eps.iter_mut().enumerate() {
                *eg = creep::eta(&self.state.creep[8 * e + g], c);
            }
        }
        let mut volumetric = [0.0; 8];
        let concrete = self.frame.tables.concrete[e];
        match temps {
            Some(step) if concrete && !step.1.inside.is_empty() => {
                self.day_weighted_strains(e, c, step, &mut volumetric);
            }
            _ => {
                let thermal =
                    self.frame.settings.thermal_strain && self.frame.tables.alpha[e] != 0.0;
                if let (true, Some((_, temps, _))) = (thermal, temps) {
                    let [t_a, t_b] = self.gauss_temperatures(e, temps.start, temps.end);
                    for g in 0..8 {
                        volumetric[g] += self.frame.tables.alpha[e] * (t_b[g] - t_a[g]);
                    }
                }
                if let (Some(law), true) = (&self.frame.settings.concrete.autogenous, concrete) {
                    let dg = law.increment(c.age0, c.age1);
                    volumetric.iter_mut().for_each(|v| *v += dg);
                }
            }
        }
        for (eg, v) in eps.iter_mut().zip(volumetric) {
            for e in &mut eg[..3] {
                *e += v;
            }
        }
        eps
    }

    /// The thermal and autogenous strains of concrete element `e`
    /// (coefficients `c`) over a step spanning several days, added to
    /// `volumetric` per Gauss point: each day's α ΔT and autogenous change
    /// weighted by the modulus at the day's mid-age against the step's,
    /// E(τ_k)/E(τ̄). A restrained element then takes the stress of daily
    /// steps, Σ E(τ_k) α ΔT_k, where α (T₁ − T₀) at the one mid-step modulus
    /// would take young concrete's hydration heat, most of it in its first
    /// days, as if the concrete were as stiff then as at mid-step (the
    /// demo's deciding apertures with 3-day steps: 0.082 against 0.171 mm
    /// from the exact path's). Days before the element's birth count
    /// nothing: a lift born inside the step strains from the temperatures
    /// at its pour.
    fn day_weighted_strains(
        &self,
        e: usize,
        c: &StepCoefficients,
        (t0, temps, t1): (f64, StepTemperatures, f64),
        volumetric: &mut [f64; 8],
    ) {
        let birth = self.state.birth_day[e];
        let settings = &self.frame.settings;
        let alpha = if settings.thermal_strain {
            self.frame.tables.alpha[e]
        } else {
            0.0
        };
        let points: Vec<(f64, &[f64])> = std::iter::once((t0, temps.start))
            .chain(temps.inside.iter().map(|(t, v)| (*t, v.as_slice())))
            .chain(std::iter::once((t1, temps.end)))
            .collect();
        for pair in points.windows(2) {
            let ((a, before), (b, after)) = (pair[0], pair[1]);
            let (age_a, age_b) = ((a - birth).max(0.0), b - birth);
            if age_b <= 0.0 {
                continue;
            }
            let weight = settings.concrete.modulus.modulus_at(0.5 * (age_a + age_b)) / c.e_mid;
            if alpha != 0.0 {
                let [t_a, t_b] = self.gauss_temperatures(e, before, after);
                for g in 0..8 {
                    volumetric[g] += weight * alpha * (t_b[g] - t_a[g]);
                }
            }
            if let Some(law) = &settings.concrete.autogenous {
                let dg = weight * law.increment(age_a, age_b);
                volumetric.iter_mut().for_each(|v| *v += dg);
            }
        }
    }

    /// External load increments of the step per global dof (the weight of
    /// the newborn elements, the change of the water load) and the new water
    /// load.
    fn external_loads(&self, water_level: Option<f64>) -> Result<(Vec<f64>, Vec<f64>), MechError> {
        let mut df_ext = vec![0.0; self.state.u.len()];
        if self.frame.settings.self_weight {
            for el in &self.sys.elements {
                let e = el.elem as usize;
                if !self.state.weight_applied[e] {
                    let w = elasticity::body_force_at(
                        &self.frame.tables.gauss[e],
                        [0.0, 0.0, -self.frame.tables.density[e] * GRAVITY],
                    );
                    let gd = elasticity::element_dofs(&self.frame.elements[e]);
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
        Ok((df_ext, water))
    }

    /// The prescribed increments in the reduced unknowns; each is used by
    /// one step only.
    fn take_prescribed(&mut self) -> Result<Prescribed, MechError> {
        let n = self.sys.n;
        let mut prescribed = Prescribed {
            system: vec![0.0; n],
            condensed: Vec::new(),
        };
        for &(g, v) in &self.prescribed {
            match self.sys.index_of[g as usize] {
                NONE => {
                    return Err(MechError::NotSupported {
                        node: g / 3,
                        comp: (g % 3) as u8,
                    })
                }
                i if i as usize >= n => prescribed.condensed.push((i - n as u32, v)),
                i => prescribed.system[i as usize] = v,
            }
        }
        self.prescribed.clear();
        Ok(prescribed)
    }

    /// The loads `b` (over [`LiveSystem::n_all`]) on the system without the
    /// condensed rock: b_D − A_DR A_RR⁻¹ b_R, with the rock's b_R, which
    /// [`MechanicsModel::recover`] takes.
    fn condense(
        &mut self,
        mut b: Vec<f64>,
        held: &[(u32, f64)],
        day: f64,
    ) -> Result<(Vec<f64>, Condensed), MechError> {
        let Some(rock) = &self.sys.rock else {
            return Ok((b, None));
        };
        let t = Instant::now();
        let b_r = b.split_off(self.sys.n);
        let y = if held.is_empty() && b_r.iter().all(|&v| v == 0.0) {
            b_r
        } else {
            self.stats.rock_solves += 1;
            rock.condense(&b_r, held, &self.sys.index_of, &mut b)
                .map_err(|source| MechError::Solve { day, source })?
        };
        self.stats.seconds_rock += t.elapsed().as_secs_f64();
        Ok((b, Some(y)))
    }

    /// The step's solution `x_d` with the condensed rock's unknowns after
    /// it (x_R = A_RR⁻¹ (b_R − A_RD x_D)).
    fn recover(
        &mut self,
        mut x_d: Vec<f64>,
        condensed: Condensed,
        day: f64,
    ) -> Result<Vec<f64>, MechError> {
        let (Some(rock), Some(y)) = (&self.sys.rock, condensed) else {
            return Ok(x_d);
        };
        let t = Instant::now();
        let x_r = rock
            .recover(&y, &self.sys.index_of, &x_d)
            .map_err(|source| MechError::Solve { day, source })?;
        x_d.extend(x_r);
        self.stats.rock_solves += 1;
        self.stats.seconds_rock += t.elapsed().as_secs_f64();
        Ok(x_d)
    }

    /// The step with joints: the contact solve of [`contact_step`].
    fn solve_joints(
        &mut self,
        a: &SparseSym,
        b: &[f64],
        prescribed: &[f64],
        day: f64,
        prepared: Option<Prepared>,
    ) -> Result<Vec<f64>, MechError> {
        let t_joint = Instant::now();
        let step = StepSystem {
            a,
            b,
            prescribed,
            points: &self.frame.points,
            day,
        };
        let mut out = contact_step::solve(
            &step,
            &mut self.sys,
            &mut self.state.joints,
            &self.frame.joint_settings,
            prepared,
        )
        .map_err(|source| MechError::Joints { day, source })?;
        let flops = self.sys.solver.factor_flops();
        self.stats
            .count_numeric(out.factorizations, flops, out.seconds_numeric);
        self.stats.contact_iterations += out.iterations;
        self.stats.slip_force_passes += out.slip_force_passes;
        self.stats.kept_closed_tension =
            self.stats.kept_closed_tension.max(out.kept_closed_tension);
        self.stats.block_pivoting_steps += usize::from(out.block_pivoting);
        self.stats.refactor_reasons.add(&out.refactor_reasons);
        self.stats.capacitance.add(&out.capacitance);
        self.stats.seconds_joints += t_joint.elapsed().as_secs_f64() - out.seconds_numeric;
        self.joint_passes = std::mem::take(&mut out.passes);
        Ok(out.x)
    }

    /// Commits the step's solution `x`: displacements, stresses, creep
    /// states, loads, contact forces.
    fn commit(
        &mut self,
        x: &[f64],
        coeffs: &[StepCoefficients],
        pseudo: &[[[f64; 6]; 8]],
        mode_loads: &[SVector<f64, 9>],
        df_ext: &[f64],
        water: Vec<f64>,
    ) {
        let mut du = vec![0.0; self.state.u.len()];
        self.sys.expand(x, &self.frame.points, &mut du);
        // du is zero off the live nodes.
        for (u, d) in self.state.u.iter_mut().zip(&du) {
            *u += d;
        }
        for (slot, el) in self.sys.elements.iter().enumerate() {
            let e = el.elem as usize;
            let gd = elasticity::element_dofs(&self.frame.elements[e]);
            let ue: [f64; 24] = std::array::from_fn(|k| du[gd[k] as usize]);
            let c = &coeffs[slot];
            let nu = Poisson(self.frame.tables.nu[e]);
            // the incompatible modes' amplitudes (E cancels: loads at E = 1)
            let modes = self
                .frame
                .tables
                .modes
                .get(e)
                .map(|m| (m, m.amplitudes(&ue, &mode_loads[slot])));
            for (g, (gauss, imposed)) in self.frame.tables.gauss[e]
                .iter()
                .zip(&pseudo[slot])
                .enumerate()
            {
                let mut deps = elasticity::strain(gauss, &ue);
                if let Some((m, alpha)) = &modes {
                    for (d, x) in deps.iter_mut().zip(m.strain(g, alpha)) {
                        *d += x;
                    }
                }
                let net: [f64; 6] = std::array::from_fn(|k| deps[k] - imposed[k]);
                let ds = nu.q_apply(&net).map(|v| c.e_eff * v);
                for (s, d) in self.state.stress[e][g].iter_mut().zip(ds) {
                    *s += d;
                }
                if !self.state.creep.is_empty() && self.frame.tables.concrete[e] {
                    creep::commit(&mut self.state.creep[8 * e + g], c, nu, &ds);
                }
            }
            if self.frame.settings.self_weight {
                self.state.weight_applied[e] = true;
            }
        }
        for (f, d) in self.state.f_ext.iter_mut().zip(df_ext) {
            *f += d;
        }
        self.state.water_load = water;
        self.state.f_contact.iter_mut().for_each(|f| *f = 0.0);
        for (p, pt) in self.frame.points.iter().enumerate() {
            let st = &self.state.joints[p];
            if !st.paired {
                continue;
            }
            let global = pt.frame.to_global(st.force);
            for (c, g) in global.iter().enumerate() {
                self.state.f_contact[3 * pt.b as usize + c] += g;
                self.state.f_contact[3 * pt.a as usize + c] -= g;
            }
        }
    }

    /// The step without joints: supports only, one factorisation, one solve.
    fn solve_plain(
        &mut self,
        mut a: SparseSym,
        mut b: Vec<f64>,
        prescribed: &[f64],
        day: f64,
    ) -> Result<Vec<f64>, MechError> {
        let sys = &mut self.sys;
        a.apply_dirichlet_with_rhs(&sys.supported, prescribed, &mut b);
        let t_num = Instant::now();
        sys.solver
            .factorize(&a)
            .map_err(|source| MechError::Solve { day, source })?;
        let flops = sys.solver.factor_flops();
        self.stats
            .count_numeric(1, flops, t_num.elapsed().as_secs_f64());
        let t_solve = Instant::now();
        let mut x = b.clone();
        sys.solver
            .solve_in_place(&mut x)
            .map_err(|source| MechError::Solve { day, source })?;
        self.stats.seconds_solve += t_solve.elapsed().as_secs_f64();
        let residual = crate::fem::relative_residual(&a, &x, &b);
        if residual.is_nan() || residual > RESIDUAL_TOLERANCE {
            return Err(MechError::Residual { day, residual });
        }
        Ok(x)
    }

    /// ‖Σ Bᵀσ − f_ext − f_contact‖ / ‖f_ext + f_contact‖ (or the internal-force
    /// scale when no load) over the free dofs live in the last step (0
    /// before the first): the accumulated stresses must balance the
    /// accumulated loads and joint forces.
    pub fn equilibrium_residual(&self) -> f64 {
        let (r, scale) = self.equilibrium_residual_parts();
        r / scale
    }

    /// The two parts of [`equilibrium_residual`](Self::equilibrium_residual):
    /// the residual norm ‖Σ Bᵀσ − f_ext − f_contact‖ over the free live dofs
    /// \[N\] and the scale it is divided by (‖f_ext + f_contact‖, or the
    /// largest internal nodal force when that is larger; never 0) \[N\]. In a
    /// state that nothing loads (blocks contracting freely) both are
    /// round-off and their ratio means nothing: a caller that knows the
    /// load that strained the model (E·α·ΔT over a section) divides by that
    /// instead (`tests/it/hard_cases.rs`).
    pub fn equilibrium_residual_parts(&self) -> (f64, f64) {
        let sys = &self.sys;
        let mut fint = vec![0.0; self.state.u.len()];
        let mut live = vec![false; self.state.u.len()];
        let mut scale = 0.0f64;
        for el in &sys.elements {
            let e = el.elem as usize;
            let f = elasticity::internal_force(&self.frame.tables.gauss[e], &self.state.stress[e]);
            let gd = elasticity::element_dofs(&self.frame.elements[e]);
            for k in 0..24 {
                fint[gd[k] as usize] += f[k];
                live[gd[k] as usize] = true;
                scale = scale.max(f[k].abs());
            }
        }
        let (mut r2, mut f2) = (0.0, 0.0);
        let mut r = vec![0.0; fint.len()];
        for d in (0..fint.len()).filter(|&d| live[d]) {
            let f = self.state.f_ext[d] + self.state.f_contact[d];
            r[d] = fint[d] - f;
            if !self.frame.supported[d] {
                f2 += f * f;
            }
        }
        // a tied node is in equilibrium only with its masters (Tᵀ r = 0)
        sys.fold_tied(&mut r);
        for d in (0..fint.len()).filter(|&d| live[d] && !self.frame.supported[d]) {
            r2 += r[d] * r[d];
        }
        (r2.sqrt(), f2.sqrt().max(scale).max(f64::MIN_POSITIVE))
    }

    /// The joint at a grouting-zone point: aperture, state label and
    /// pressure, bilinear over the joint points of its face (a node
    /// shared with the rock is closed, and carries no stress of the joint's).
    /// None until both blocks exist there.
    pub fn point_aperture(&self, mesh: &Mesh, zp: &ZoneSite) -> Option<JointReading> {
        let pair = &mesh.face_pairs[zp.pair as usize];
        let n = crate::fem::quad4::shape([zp.s, zp.t]);
        let (mut value, mut label, mut best) = (0.0, JointState::Stick, -1.0);
        let (mut pressure, mut weight) = (0.0, 0.0);
        for (k, &nk) in n.iter().enumerate() {
            if pair.nodes_a[k] == pair.nodes_b[k] {
                continue;
            }
            let p = *self.frame.point_of_a.get(&pair.nodes_a[k])? as usize;
            let st = &self.state.joints[p];
            if !st.paired {
                return None;
            }
            value += nk * st.aperture();
            pressure += nk * self.joint_pressure(p);
            weight += nk;
            if nk > best {
                best = nk;
                label = st.label();
            }
        }
        Some(JointReading {
            aperture: value,
            state: label,
            pressure: if weight > 0.0 { pressure / weight } else { 0.0 },
        })
    }

    /// Pressure across the joint \[Pa\] at joint point `p`, compression
    /// positive: its normal force (which presses side B when positive) over
    /// its tributary area; exact for a uniform traction on the bilinear
    /// joint faces.
    pub fn joint_pressure(&self, p: usize) -> f64 {
        self.state.joints[p].force[2] / self.frame.points[p].area
    }

    /// The zone's smallest aperture inside its grout stops: the minimum of
    /// the aperture field over its samples ([`super::grout_stops`]). None
    /// until both blocks exist at one of them.
    pub fn zone_min_aperture(&self, joint: u32, zone: u32) -> Option<ZoneMinimum> {
        self.frame
            .zone_stop_samples
            .get(&(joint, zone))?
            .iter()
            .filter_map(|s| self.sample_aperture(s))
            .min_by(|x, y| x.reading.aperture.total_cmp(&y.reading.aperture))
    }

    /// The aperture field at one sample, with its state: the heavier
    /// point's, except that a sample between an open point and a closed one
    /// is open (its aperture weighs in the opening).
    fn sample_aperture(&self, s: &StopSample) -> Option<ZoneMinimum> {
        let used = if s.weights[1] > 0.0 { 2 } else { 1 };
        let st: Vec<&JointPointState> = s.points[..used]
            .iter()
            .map(|&p| &self.state.joints[p as usize])
            .collect();
        if st.iter().any(|p| !p.paired) {
            return None;
        }
        let aperture = (0..used).map(|k| s.weights[k] * st[k].aperture()).sum();
        let heavier = usize::from(used == 2 && s.weights[1] > s.weights[0]);
        let mut state = st[heavier].label();
        if st
            .iter()
            .any(|p| p.label() == JointState::Open && p.aperture() > 0.0)
        {
            state = JointState::Open;
        }
        let pressure = (0..used)
            .map(|k| s.weights[k] * self.joint_pressure(s.points[k] as usize))
            .sum();
        let node = |k: usize| self.frame.points[s.points[k] as usize].a;
        Some(ZoneMinimum {
            reading: JointReading {
                aperture,
                state,
                pressure,
            },
            nodes: [(node(0), s.weights[0]), (node(1), s.weights[1])],
        })
    }

    /// Number of mechanical dofs live in the last step (0 before the
    /// first), the condensed rock's included.
    pub fn live_dofs(&self) -> usize {
        self.sys.n_all()
    }

    /// The rows of the live joint pairs and their neighbours, which a
    /// contact pass reads (gaps, and reactions through K̃), and the rows and
    /// entries of L on the union of their reaches: the part of a backward
    /// half a pass would need before its states are known (a measurement
    /// for `study perf`).
    pub fn joint_rows_reach(&self) -> (usize, usize, usize) {
        let live = &self.sys;
        let mut pair_row = vec![false; live.n];
        for p in &live.pairs {
            for k in 0..3 {
                pair_row[p.first as usize + k] = true;
            }
        }
        let mut read = pair_row.clone();
        let (cp, ri) = (live.pattern.col_ptr(), live.pattern.row_idx());
        for j in 0..live.n {
            for &i in &ri[cp[j] as usize..cp[j + 1] as usize] {
                let i = i as usize;
                read[j] |= pair_row[i];
                read[i] |= pair_row[j];
            }
        }
        let dofs: Vec<usize> = (0..live.n).filter(|&i| read[i]).collect();
        let (rows, entries) = live.solver.reach_size(&dofs);
        (dofs.len(), rows, entries)
    }

    /// The contact passes of the last step with joint pairs, one record
    /// each (empty before such a step, and after a `qp` step).
    pub fn joint_passes(&self) -> &[PassRecord] {
        &self.joint_passes
    }

    /// Entries of the live system's Cholesky factor and the flops of one
    /// numeric factorisation (see [`CholeskySolver::factor_flops`](crate::fem::CholeskySolver::factor_flops)).
    pub fn factor_size(&self) -> (usize, f64) {
        (self.sys.solver.factor_nnz(), self.sys.solver.factor_flops())
    }
}

/// Whether point `pt`, in state `st`, takes grout when `zone` is grouted:
/// a live pair of the zone not grouted yet. [`MechanicsModel::grout`] and
/// the guess of a grouting day's factor select the same points by it.
fn takes_grout(pt: &JointPoint, st: &JointPointState, zone: ZoneId) -> bool {
    pt.joint == zone.joint && pt.zone == zone.zone && st.paired && st.grout.is_none()
}

/// [`super::rock_condensation::CondensedRock::condense`]'s y = A_RR⁻¹ b_R, when the rock is condensed.
type Condensed = Option<Vec<f64>>;

/// A step's prescribed increments: over the system's unknowns, and the
/// condensed rock's (its index, the increment).
struct Prescribed {
    system: Vec<f64>,
    condensed: Vec<(u32, f64)>,
}

/// Whether the settings let a step be factorised ahead: the active set
/// with the capacitance correction (which takes the rows that changed
/// since), and `solver.factor_ahead`.
fn factor_ahead(settings: &MechanicsSettings) -> bool {
    let j = &settings.joint;
    settings.factor_ahead && j.capacitance && j.solver == crate::scene::ContactSolverKind::ActiveSet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_concrete_keeps_creep_terms() {
        let s = MechState::before_pours(16, &[true, false, true], 0, 2);
        let terms: Vec<usize> = s.creep.iter().map(|c| c.omega.len()).collect();
        assert_eq!(terms.len(), 24);
        assert!(terms[..8].iter().chain(&terms[16..]).all(|&n| n == 2));
        assert!(terms[8..16].iter().all(|&n| n == 0));
        assert!(MechState::before_pours(16, &[true, false], 0, 0)
            .creep
            .is_empty());
    }

    #[test]
    fn tension_kept_closed_is_warned_of_in_megapascals() {
        let mut m = MechStats::default();
        assert_eq!(m.kept_tension_warning(), "");
        m.kept_closed_tension = 1.5e6;
        let w = m.kept_tension_warning();
        assert!(
            w.starts_with("warning: ") && w.contains("up to 1.500 MPa"),
            "{w}"
        );
    }
}
