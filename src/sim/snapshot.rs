//! What a VTU snapshot of the live mesh shows, handed out by the simulation
//! (the caller writes it): temperature per node; block, lift, stresses per
//! cell; displacement, joint aperture, pressure and state on joint nodes.

use chrono::NaiveDate;

use crate::mesh::Part;
use crate::vocab::Day;

use super::Simulation;

/// The fields of one snapshot, named as ParaView shows them.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    pub day: Day,
    pub date: NaiveDate,
    /// the elements that exist on the day
    pub live: Vec<u32>,
    /// (name, one value per mesh node)
    pub point_fields: Vec<(String, Vec<f64>)>,
    /// (name, one value per mesh element)
    pub cell_fields: Vec<(String, Vec<f64>)>,
}

impl Simulation<'_> {
    /// The fields of the current state (a whole day).
    pub fn snapshot(&self) -> Snapshot {
        let mesh = self.mesh;
        let live: Vec<u32> = match &self.thermal {
            Some(th) => (0..mesh.elements.len() as u32)
                .filter(|&e| th.state.live[e as usize])
                .collect(),
            None => (0..mesh.elements.len() as u32).collect(),
        };
        let temperature: Vec<f64> = match &self.thermal {
            Some(th) => th.nodal_field(mesh),
            None => vec![f64::NAN; mesh.nodes.len()],
        };
        let block: Vec<f64> = mesh
            .parts
            .iter()
            .map(|p| match p {
                Part::Concrete { block, .. } => *block as f64,
                Part::Rock => 0.0,
            })
            .collect();
        let lift: Vec<f64> = mesh
            .parts
            .iter()
            .map(|p| match p {
                Part::Concrete { lift, .. } => *lift as f64,
                Part::Rock => 0.0,
            })
            .collect();
        let mut point_fields: Vec<(String, Vec<f64>)> = vec![("temperature_c".into(), temperature)];
        let mut cell_fields: Vec<(String, Vec<f64>)> =
            vec![("block".into(), block), ("lift".into(), lift)];
        if let Some(m) = &self.mechanics {
            for (c, name) in ["ux_m", "uy_m", "uz_m"].iter().enumerate() {
                point_fields.push((
                    name.to_string(),
                    (0..mesh.nodes.len())
                        .map(|i| m.state.u[3 * i + c])
                        .collect(),
                ));
            }
            // Element means of the Gauss-point stresses, in MPa as engineers read them.
            let mean = |e: usize, k: usize| {
                m.state.stress[e].iter().map(|g| g[k]).sum::<f64>() / 8.0 * 1e-6
            };
            for (k, name) in [
                "sxx_mpa", "syy_mpa", "szz_mpa", "sxy_mpa", "syz_mpa", "szx_mpa",
            ]
            .iter()
            .enumerate()
            {
                cell_fields.push((
                    name.to_string(),
                    (0..mesh.elements.len()).map(|e| mean(e, k)).collect(),
                ));
            }
            let vm = (0..mesh.elements.len())
                .map(|e| {
                    let s: [f64; 6] = std::array::from_fn(|k| mean(e, k));
                    crate::fem::von_mises(&s)
                })
                .collect();
            cell_fields.push(("von_mises_mpa".into(), vm));
            if !m.points().is_empty() {
                // On both nodes of each joint pair: aperture [mm], normal
                // pressure [MPa] and a state code; NaN off the joints.
                let n = mesh.nodes.len();
                let (mut aperture, mut pressure, mut code) =
                    (vec![f64::NAN; n], vec![f64::NAN; n], vec![f64::NAN; n]);
                for (p, pt) in m.points().iter().enumerate() {
                    let st = &m.state.joints[p];
                    if !st.paired {
                        continue;
                    }
                    let c = st.label().code();
                    for node in [pt.a as usize, pt.b as usize] {
                        aperture[node] = 1e3 * st.aperture();
                        pressure[node] = 1e-6 * m.joint_pressure(p);
                        code[node] = c;
                    }
                }
                point_fields.push(("joint_aperture_mm".into(), aperture));
                point_fields.push(("joint_pressure_mpa".into(), pressure));
                point_fields.push((
                    "joint_state_1open_2stick_3slip_4grouted_5reopened".into(),
                    code,
                ));
            }
        }
        let day = Day::containing(self.day);
        Snapshot {
            day,
            date: self.scene.epoch.date(day),
            live,
            point_fields,
            cell_fields,
        }
    }
}
