//! Per-element thermal data computed once per run: dofs, conductivity matrix
//! and lumped capacity. Material properties do not age in the thermal
//! problem, so these never change; only which elements are live does.

use nalgebra::SMatrix;

use crate::fem::hex8::FACES;
use crate::fem::thermal_kernels;
use crate::fem::ElementError;
use crate::mesh::{Mesh, Part};
use crate::scene::{Scene, ThermalProperties};

type Mat8 = SMatrix<f64, 8, 8>;

#[derive(Debug, thiserror::Error)]
pub enum ElementDataError {
    #[error("the mesh has rock elements but the scene has no [rock] table")]
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
}

impl ElementData {
    pub fn new(mesh: &Mesh, scene: &Scene) -> Result<ElementData, ElementDataError> {
        let n = mesh.elements.len();
        let mut data = ElementData {
            coords: Vec::with_capacity(n),
            dofs: Vec::with_capacity(n),
            rho_c: Vec::with_capacity(n),
            ke: Vec::with_capacity(n),
            cap_lumped: Vec::with_capacity(n),
        };
        let c = &scene.concrete;
        for (e, conn) in mesh.elements.iter().enumerate() {
            let coords: [[f64; 3]; 8] = std::array::from_fn(|k| mesh.nodes[conn[k] as usize]);
            let (rho_c, lambda_day) = match mesh.parts[e] {
                Part::Concrete { .. } => (c.heat_capacity_j_m3k(), c.conductivity_j_per_m_day_k()),
                Part::Rock => {
                    // scene validation guarantees [rock] when the mesh has rock
                    let r = scene.rock.as_ref().ok_or(ElementDataError::NoRock)?;
                    (r.heat_capacity_j_m3k(), r.conductivity_j_per_m_day_k())
                }
            };
            data.ke
                .push(thermal_kernels::conductivity(&coords, lambda_day)?);
            data.cap_lumped
                .push(thermal_kernels::capacity_lumped(&coords, rho_c)?);
            data.dofs
                .push(std::array::from_fn(|k| mesh.thermal_dof[conn[k] as usize]));
            data.rho_c.push(rho_c);
            data.coords.push(coords);
        }
        Ok(data)
    }

    pub fn cap_consistent(&self, e: usize) -> Mat8 {
        thermal_kernels::capacity_consistent(&self.coords[e], self.rho_c[e])
            .expect("element Jacobians were checked when the element data was built")
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

    /// Σ c_k T_k over the element: its stored heat [J].
    pub fn stored_heat(&self, e: usize, temperature: &[f64]) -> f64 {
        self.cap_lumped[e]
            .iter()
            .zip(self.dofs[e].iter())
            .map(|(c, &d)| c * temperature[d as usize])
            .sum()
    }
}
