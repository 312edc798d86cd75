//! What the thermal model needs of a scene, resolved once: material
//! constants in the units the model computes in (J, m, day, °C), the effects
//! as present-or-absent laws, and the time-stepping and solver choices.

use crate::material::{AdiabaticRise, ZhuPipe};
use crate::scene::{CapacityKind, Effect, Scene, ThermalProperties, ThermalSolverKind};

/// Heat-conduction constants of one material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalMaterial {
    /// Volumetric heat capacity ρc [J/(m³ K)].
    pub heat_capacity_j_m3k: f64,
    /// Conductivity λ per day [J/(m day K)] (the scene gives W/(m K)).
    pub conductivity_j_per_m_day_k: f64,
}

/// The foundation rock: its material and its field before construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RockThermal {
    pub material: ThermalMaterial,
    /// Initial temperature at the elevation of the dam's base
    /// (`Mesh::layer_z[0]`) [°C]; the rock below is warmer by the gradient.
    pub initial_temp_c: f64,
    /// Initial gradient, positive = warmer with depth [°C/m].
    pub gradient_c_per_m: f64,
}

/// Settings of the thermal model ([`ThermalModel::new`](super::ThermalModel::new)).
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalSettings {
    /// The dam concrete.
    pub concrete: ThermalMaterial,
    /// The foundation rock; `None` for a scene without `[rock]` (then the
    /// mesh must have no rock elements).
    pub rock: Option<RockThermal>,
    /// Adiabatic temperature rise θ(τ) [°C, τ in days] of the concrete; `None`
    /// without the `hydration` effect (no heat of hydration).
    pub rise: Option<AdiabaticRise>,
    /// Zhu's equivalent pipe cooling of the scene's pipe layout; `None`
    /// without the `pipe_cooling` effect (cooling stages are then ignored).
    pub pipe: Option<ZhuPipe>,
    /// The `ambient` effect: convection to the air on exposed faces.
    pub ambient: bool,
    /// The `reservoir_temperature` effect: water temperature on submerged faces.
    pub reservoir_temperature: bool,
    /// θ of the θ-method, in [0.5, 1] (1 = backward Euler).
    pub theta: f64,
    /// Lumped (row-summed) or consistent capacity matrix.
    pub capacity: CapacityKind,
    /// Sparse Cholesky or Jacobi-preconditioned conjugate gradients.
    pub solver: ThermalSolverKind,
    /// PCG stops at ‖r‖ ≤ pcg_tolerance·‖b‖ (relative, dimensionless).
    pub pcg_tolerance: f64,
    /// PCG iterations after which a step fails.
    pub pcg_max_iterations: usize,
    /// Fixed temperature [°C] of each far side, in
    /// [`FarSide::ALL`](crate::mesh::FarSide::ALL) order; `None` = adiabatic.
    pub far_temperature_c: [Option<f64>; 5],
    /// A pour resets the nodes its lift shares with live concrete or rock
    /// to the placement temperature (`concrete.placement_on_shared_nodes =
    /// "placement"`); false keeps theirs (default).
    pub placement_on_shared_nodes: bool,
}

impl ThermalSettings {
    /// The settings of a validated scene. Reads `[concrete]` (density,
    /// specific heat, conductivity, `adiabatic`), `[rock]` (the same three,
    /// `initial_temp_c`, `gradient_c_per_m`), `[pipes]`, `effects`
    /// (`hydration`, `pipe_cooling`, `ambient`, `reservoir_temperature`),
    /// `[time]` (`theta`, `capacity`), `[solver]` (`thermal`,
    /// `pcg_tolerance`, `pcg_max_iterations`) and `[boundary]` (the far
    /// sides' `temperature_c`). Every one of them is either
    /// required by the scene or has its default there; an effect without its
    /// table (refused by the scene's validation) is off.
    pub fn from_scene(scene: &Scene) -> ThermalSettings {
        let c = &scene.concrete;
        let pipe = scene
            .pipes
            .as_ref()
            .filter(|_| scene.has(Effect::PipeCooling))
            .map(|layout| {
                ZhuPipe::new(
                    layout,
                    scene.concrete_diffusivity_m2_per_day(),
                    c.conductivity_w_mk,
                )
            });
        ThermalSettings {
            concrete: ThermalMaterial {
                heat_capacity_j_m3k: c.heat_capacity_j_m3k(),
                conductivity_j_per_m_day_k: c.conductivity_j_per_m_day_k(),
            },
            rock: scene.rock.as_ref().map(|r| RockThermal {
                material: ThermalMaterial {
                    heat_capacity_j_m3k: r.heat_capacity_j_m3k(),
                    conductivity_j_per_m_day_k: r.conductivity_j_per_m_day_k(),
                },
                initial_temp_c: r.initial_temp_c,
                gradient_c_per_m: r.gradient_c_per_m,
            }),
            rise: c.adiabatic.clone().filter(|_| scene.has(Effect::Hydration)),
            pipe,
            ambient: scene.has(Effect::Ambient),
            reservoir_temperature: scene.has(Effect::ReservoirTemperature),
            theta: scene.time.theta,
            capacity: scene.time.capacity,
            solver: scene.solver.thermal,
            pcg_tolerance: scene.solver.pcg_tolerance,
            pcg_max_iterations: scene.solver.pcg_max_iterations as usize,
            far_temperature_c: scene.boundary.temperatures(),
            placement_on_shared_nodes: c.placement_on_shared_nodes
                == crate::scene::SharedNodes::Placement,
        }
    }
}
