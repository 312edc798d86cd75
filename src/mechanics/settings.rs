//! What the mechanical model needs of a scene, resolved once: the
//! materials' laws and constants (SI units, ages in days), the effects, and
//! the joints' contact and grout parameters.

use crate::material::{AutogenousLaw, CreepLaw, ModulusLaw};
use crate::scene::{ContactSolverKind, Effect, OrderingKind, Scene, SolidElement};
use crate::vocab::Invalid;

/// Poisson's ratio of a rock whose scene gives none (`rock.poisson` absent).
pub const DEFAULT_ROCK_POISSON: f64 = 0.25;
/// Thermal expansion [1/°C] of a material whose scene gives none: it does not
/// strain with temperature. Validation asks for `concrete.expansion_per_c`
/// with the `thermal_strain` effect, so in practice this is the rock's
/// default (`rock.expansion_per_c` absent).
pub const NO_THERMAL_EXPANSION: f64 = 0.0;

/// The dam concrete.
#[derive(Debug, Clone, PartialEq)]
pub struct ConcreteMechanics {
    /// Ageing elastic modulus E(τ) \[Pa\], τ the age in days.
    pub modulus: ModulusLaw,
    /// Poisson's ratio ν [-], constant in time.
    pub poisson: f64,
    /// Linear thermal expansion α [1/°C].
    pub expansion_per_c: f64,
    /// Density ρ [kg/m³] (self-weight).
    pub density_kg_m3: f64,
    /// Creep compliance; `None` without the `creep` effect (no creep).
    pub creep: Option<CreepLaw>,
    /// Autogenous volume change G(τ) [-]; `None` without the `autogenous`
    /// effect.
    pub autogenous: Option<AutogenousLaw>,
}

/// The foundation rock: elastic, not ageing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RockMechanics {
    /// Elastic modulus E \[Pa\].
    pub modulus_pa: f64,
    /// Poisson's ratio ν [-].
    pub poisson: f64,
    /// Linear thermal expansion α [1/°C].
    pub expansion_per_c: f64,
    /// Density ρ [kg/m³] (its weight never strains it: see the model).
    pub density_kg_m3: f64,
}

/// The transverse joints' contact and grout parameters (the scene's
/// `[joints]` and the contact keys of `[solver]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointMechanics {
    /// Active set or condensed cone program.
    pub solver: ContactSolverKind,
    /// Contact passes (active set) or cracking rounds (qp) per step before
    /// the step fails.
    pub max_iterations: usize,
    /// Static Coulomb coefficient μ_s [-] of an ungrouted joint.
    pub mu_static: f64,
    /// Kinetic Coulomb coefficient μ_k ≤ μ_s [-].
    pub mu_kinetic: f64,
    /// Gap of a joint point when its second block is poured \[m\].
    pub initial_gap_m: f64,
    /// Normal modulus E_z of the grout layer \[Pa\].
    pub grout_modulus_pa: f64,
    /// Shear modulus G_x = G_y of the grout layer \[Pa\].
    pub grout_shear_modulus_pa: f64,
    /// Thinnest grout layer \[m\]: a smaller aperture is grouted this thick.
    pub grout_min_thickness_m: f64,
    /// Tensile bond strength of a grouted point \[Pa\]; above it the layer cracks.
    pub bond_strength_pa: f64,
    /// Capacitance correction of contact-set changes (`solver.contact_capacitance`).
    pub capacitance: bool,
    /// Distance of the grout stops from the upstream and downstream faces
    /// \[m\], along the joint face: the zone minimum is read inside them
    /// ([`super::grout_stops`]); None: at the joint nodes off the faces.
    pub grout_stop_inset_m: Option<f64>,
}

/// Settings of the mechanical model ([`MechanicsModel::new`](super::MechanicsModel::new)).
#[derive(Debug, Clone, PartialEq)]
pub struct MechanicsSettings {
    pub concrete: ConcreteMechanics,
    /// `None` for a scene without `[rock]` (then the mesh must have no rock
    /// elements).
    pub rock: Option<RockMechanics>,
    /// The `thermal_strain` effect: temperature changes strain the materials.
    pub thermal_strain: bool,
    /// The `self_weight` effect: each element's weight is applied at its birth.
    pub self_weight: bool,
    /// The `reservoir_load` effect: hydrostatic pressure on the wet faces.
    pub reservoir_load: bool,
    /// The `joints` effect: contact points on the transverse joints.
    pub joints: bool,
    /// Contact and grout parameters (used with `joints`).
    pub joint: JointMechanics,
    /// Fill-reducing ordering of the step's factorisation (`solver.ordering`).
    pub ordering: OrderingKind,
    /// The solid element (`solver.element`).
    pub element: SolidElement,
    /// Factorise each step's stiffness on the second core while the step
    /// before runs its contact passes (`solver.factor_ahead`).
    pub factor_ahead: bool,
    /// Keep every N-th node level of the rock beside the dam and tie the
    /// others to them (`solver.rock_coarsening`; 1: none;
    /// [`super::rock_ties`]).
    pub rock_coarsening: u32,
    /// Condense the rock no step changes once per run
    /// (`solver.condense_rock`; [`super::rock_condensation`]).
    pub condense_rock: bool,
    /// Tie the concrete between the zone boundaries once this many days
    /// old (`solver.layer_merging_age_days`; 0: off; [`super::layer_merging`]).
    pub layer_merging_age_days: u32,
}

impl MechanicsSettings {
    /// The settings of a validated scene with a mechanical effect. Reads
    /// `effects`, `[concrete]` (`modulus`, `poisson`, `expansion_per_c`,
    /// `density_kg_m3`, `creep`, `autogenous`), `[rock]` (`modulus_pa`,
    /// `poisson`, `expansion_per_c`, `density_kg_m3`), `[joints]` (friction,
    /// initial gap, grout, grout stops) and `[solver]` (`contact`,
    /// `contact_max_iterations`, `contact_capacitance`, `ordering`). `rock.poisson` defaults to
    /// [`DEFAULT_ROCK_POISSON`], an absent expansion to
    /// [`NO_THERMAL_EXPANSION`]; creep and autogenous laws count only with
    /// their effects.
    ///
    /// `Err` names `concrete.modulus`, `concrete.poisson` or (with a `[rock]`
    /// table) `rock.modulus_pa` when missing: the scene's validation refuses
    /// a mechanical effect without them, so only a scene built in code gets
    /// here without them.
    pub fn from_scene(scene: &Scene) -> Result<MechanicsSettings, Invalid> {
        let c = &scene.concrete;
        let j = &scene.joints;
        let rock = match &scene.rock {
            Some(r) => Some(RockMechanics {
                modulus_pa: required(r.modulus_pa, "rock.modulus_pa")?,
                poisson: r.poisson.unwrap_or(DEFAULT_ROCK_POISSON),
                expansion_per_c: r.expansion_per_c.unwrap_or(NO_THERMAL_EXPANSION),
                density_kg_m3: r.density_kg_m3,
            }),
            None => None,
        };
        Ok(MechanicsSettings {
            concrete: ConcreteMechanics {
                modulus: required(c.modulus, "concrete.modulus")?,
                poisson: required(c.poisson, "concrete.poisson")?,
                expansion_per_c: c.expansion_per_c.unwrap_or(NO_THERMAL_EXPANSION),
                density_kg_m3: c.density_kg_m3,
                creep: c.creep.clone().filter(|_| scene.has(Effect::Creep)),
                autogenous: c.autogenous.filter(|_| scene.has(Effect::Autogenous)),
            },
            rock,
            thermal_strain: scene.has(Effect::ThermalStrain),
            self_weight: scene.has(Effect::SelfWeight),
            reservoir_load: scene.has(Effect::ReservoirLoad),
            joints: scene.has(Effect::Joints),
            joint: JointMechanics {
                solver: scene.solver.contact,
                max_iterations: scene.solver.contact_max_iterations as usize,
                capacitance: scene.solver.contact_capacitance,
                mu_static: j.mu_static,
                mu_kinetic: j.mu_kinetic,
                initial_gap_m: j.initial_gap_m,
                grout_modulus_pa: j.grout_modulus_pa,
                grout_shear_modulus_pa: j.grout_shear_modulus_pa,
                grout_min_thickness_m: j.grout_min_thickness_m,
                bond_strength_pa: j.bond_strength_pa,
                grout_stop_inset_m: j.grout_stop_inset_m,
            },
            ordering: scene.solver.ordering,
            element: scene.solver.element,
            factor_ahead: scene.solver.factor_ahead,
            rock_coarsening: scene.solver.rock_coarsening,
            condense_rock: scene.solver.condense_rock,
            layer_merging_age_days: scene.solver.layer_merging_age_days,
        })
    }
}

/// A value the scene's validation guarantees for a mechanical scene.
fn required<T>(value: Option<T>, key: &str) -> Result<T, Invalid> {
    value.ok_or_else(|| {
        Invalid::new(
            key,
            format!("{key} is missing: the mechanical effects need it"),
        )
    })
}
