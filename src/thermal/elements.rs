//! Per-element thermal data computed once per run: dofs, conductivity matrix
//! and lumped capacity. Material properties do not age in the thermal
//! problem, so these never change; only which elements are live does.

use nalgebra::SMatrix;

use crate::fem::hex8::FACES;
use crate::fem::thermal_kernels;
use crate::fem::ElementError;
use crate::mesh::{Mesh, Part};

use super::settings::ThermalSettings;
use crate::scene::CapacityKind;

type Mat8 = SMatrix<f64, 8, 8>;

#[derive(Debug, thiserror::Error)]
pub enum ElementDataError {
    #[error("the mesh has rock elements but the thermal settings have no rock (the scene's [rock] table)")]
    NoRock,
    #[error(transparent)]
    Element(#[from] ElementError),
}

/// Seconds per day: conductivities and film coefficients are given per second (W).
pub use crate::scene::SECONDS_PER_DAY;

pub struct ElementData {
    pub coords: Vec<[[f64; 3]; 8]>,
    pub dofs: Vec<[u32; 8]>,
    /// ρc [J/(m³ K)]
    pub rho_c: Vec<f64>,
    /// conductivity matrices [J/(day K)]
    pub ke: Vec<Mat8>,
    /// lumped capacities [J/K]
    pub cap_lumped: Vec<[f64; 8]>,
    /// consistent capacity matrices [J/K], when the settings ask for them:
    /// made once per run rather than at each of the live sets (a pour
    /// makes one), where their 27-point quadratures were 46 % of the
    /// live systems' making on the demo (`perf`, 28 Nov 2026)
    pub cap_consistent: Vec<Mat8>,
}

impl ElementData {
    /// The data of every element of `mesh`, live or not. The rock's
    /// settings are needed only when the mesh has rock elements (a scene's
    /// validation asks for `[rock]` whenever its geometry has rock).
    pub fn new(mesh: &Mesh, settings: &ThermalSettings) -> Result<ElementData, ElementDataError> {
        let n = mesh.elements.len();
        let mut data = ElementData {
            coords: Vec::with_capacity(n),
            dofs: Vec::with_capacity(n),
            rho_c: Vec::with_capacity(n),
            ke: Vec::with_capacity(n),
            cap_lumped: Vec::with_capacity(n),
            cap_consistent: Vec::new(),
        };
        let consistent = settings.capacity == CapacityKind::Consistent;
        for (e, conn) in mesh.elements.iter().enumerate() {
            let coords: [[f64; 3]; 8] = std::array::from_fn(|k| mesh.nodes[conn[k] as usize]);
            let material = match mesh.parts[e] {
                Part::Concrete { .. } => settings.concrete,
                Part::Rock => {
                    settings
                        .rock
                        .as_ref()
                        .ok_or(ElementDataError::NoRock)?
                        .material
                }
            };
            let (rho_c, lambda_day) = (
                material.heat_capacity_j_m3k,
                material.conductivity_j_per_m_day_k,
            );
            data.ke
                .push(thermal_kernels::conductivity(&coords, lambda_day)?);
            data.cap_lumped
                .push(thermal_kernels::capacity_lumped(&coords, rho_c)?);
            if consistent {
                data.cap_consistent
                    .push(thermal_kernels::capacity_consistent(&coords, rho_c)?);
            }
            data.dofs
                .push(std::array::from_fn(|k| mesh.thermal_dof[conn[k] as usize]));
            data.rho_c.push(rho_c);
            data.coords.push(coords);
        }
        Ok(data)
    }

    /// (∫βNNᵀdA, ∫βN dA) of local face `face` of element `e`; β per day.
    pub fn face_convection(
        &self,
        e: usize,
        face: usize,
        beta_day: f64,
    ) -> Result<(SMatrix<f64, 4, 4>, [f64; 4]), ElementError> {
        let ids = FACES[face];
        let fc: [[f64; 3]; 4] = std::array::from_fn(|k| self.coords[e][ids[k]]);
        thermal_kernels::face_convection(&fc, beta_day)
    }

    /// Σ c_k T_k over the element: its stored heat \[J\].
    pub fn stored_heat(&self, e: usize, temperature: &[f64]) -> f64 {
        self.cap_lumped[e]
            .iter()
            .zip(self.dofs[e].iter())
            .map(|(c, &d)| c * temperature[d as usize])
            .sum()
    }
}
