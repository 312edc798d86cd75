//! The linear system of the live elements: dof numbering, exposed faces,
//! sparse pattern with its symbolic Cholesky, and a small cache of numeric
//! factors keyed by the step length.
//!
//! Rebuilt only when the set of live elements changes (a pour). The boundary
//! matrices are rebuilt when the set of submerged nodes changes. Numeric
//! factorisations happen only for a step length not seen since the last
//! rebuild, so a run's factorisation count is (rebuilds × distinct Δt), which
//! the benchmark prints.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use nalgebra::SMatrix;

use crate::fem::hex8::FACES;
use crate::fem::ordering::Ordering;
use crate::fem::solver::{CholeskySolver, SolveError};
use crate::fem::sparse::{Pattern, SparseSym};
use crate::fem::ElementError;
use crate::mesh::SurfaceKind;

use super::elements::ElementData;

pub(crate) const NONE: u32 = u32::MAX;

/// Systems at least this large are factorised with all rayon threads.
const PARALLEL_FROM_DOFS: usize = 30_000;

type Mat8 = SMatrix<f64, 8, 8>;

/// Exposed face of a live element: (element, local face).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ExposedFace {
    pub elem: u32,
    pub face: u8,
    /// The mesh marks it as a face that can be under the reservoir.
    pub wet: bool,
}

/// Incremental count of element faces of the live set, keyed by their sorted
/// thermal dofs: a face owned by exactly one live element is exposed.
#[derive(Debug, Clone, Default)]
pub struct FaceCounter {
    faces: HashMap<[u32; 4], (u32, u32, u8)>, // key → (count, elem, face)
}

impl FaceCounter {
    pub fn add_element(&mut self, elem: u32, dofs: &[u32; 8]) {
        for (f, local) in FACES.iter().enumerate() {
            let mut key = [
                dofs[local[0]],
                dofs[local[1]],
                dofs[local[2]],
                dofs[local[3]],
            ];
            key.sort_unstable();
            let slot = self.faces.entry(key).or_insert((0, elem, f as u8));
            slot.0 += 1;
        }
    }

    /// Exposed faces except those on the far model boundary (adiabatic).
    pub fn exposed(&self, far: &BTreeMap<(u32, u8), SurfaceKind>) -> Vec<ExposedFace> {
        let mut out: Vec<ExposedFace> = self
            .faces
            .values()
            .filter(|(count, _, _)| *count == 1)
            .filter_map(|&(_, elem, face)| match far.get(&(elem, face)) {
                Some(SurfaceKind::Far) => None,
                Some(SurfaceKind::Wet) => Some(ExposedFace {
                    elem,
                    face,
                    wet: true,
                }),
                _ => Some(ExposedFace {
                    elem,
                    face,
                    wet: false,
                }),
            })
            .collect();
        // HashMap order is random; sort so assembly (and round-off) is reproducible.
        out.sort_unstable_by_key(|f| (f.elem, f.face));
        out
    }
}

/// Everything that depends on the live element set.
pub struct LiveSystem {
    /// live index → thermal dof
    pub dofs: Vec<u32>,
    /// thermal dof → live index or NONE
    pub index_of: Vec<u32>,
    /// live elements, in pattern slot order
    pub elems: Vec<u32>,
    /// element dofs in live numbering, per slot
    pub local_dofs: Vec<[u32; 8]>,
    pub exposed: Vec<ExposedFace>,
    pub pattern: Arc<Pattern>,
    /// lumped capacity per live dof [J/K]
    pub cap_lumped: Vec<f64>,
    /// consistent capacity, when the scene asks for it
    pub cap_consistent: Option<SparseSym>,
    /// K + H_air (no Dirichlet rows) [J/(day K)]
    pub kh: SparseSym,
    /// ∫ β N dA over air faces per live dof: the air load is this × Ta
    pub air_load: Vec<f64>,
    /// live dofs with a prescribed (water) temperature
    pub fixed: Vec<bool>,
    /// symbolic analysis; absent when the run solves by PCG
    solver: Option<CholeskySolver>,
    factors: Vec<(u64, CholeskySolver)>,
}

impl LiveSystem {
    /// The system of no live element over `n_dofs` thermal dofs: what a model
    /// holds until its first rebuild, so that no dof reads as live before then.
    pub fn empty(n_dofs: usize) -> LiveSystem {
        let pattern = Arc::new(Pattern::new(0, &[] as &[[u32; 8]]));
        LiveSystem {
            dofs: Vec::new(),
            index_of: vec![NONE; n_dofs],
            elems: Vec::new(),
            local_dofs: Vec::new(),
            exposed: Vec::new(),
            kh: SparseSym::new(pattern.clone()),
            pattern,
            cap_lumped: Vec::new(),
            cap_consistent: None,
            air_load: Vec::new(),
            fixed: Vec::new(),
            solver: None,
            factors: Vec::new(),
        }
    }

    /// Builds the numbering, pattern and symbolic factorisation for `live_elems`.
    pub fn new(
        dof_xyz: &[[f64; 3]],
        live_elems: Vec<u32>,
        data: &ElementData,
        exposed: Vec<ExposedFace>,
        consistent: bool,
        direct: bool,
    ) -> Result<LiveSystem, SolveError> {
        let mut index_of = vec![NONE; dof_xyz.len()];
        let mut dofs = Vec::new();
        let mut local_dofs = Vec::with_capacity(live_elems.len());
        for &e in &live_elems {
            let mut ld = [0u32; 8];
            for (k, &d) in data.dofs[e as usize].iter().enumerate() {
                if index_of[d as usize] == NONE {
                    index_of[d as usize] = dofs.len() as u32;
                    dofs.push(d);
                }
                ld[k] = index_of[d as usize];
            }
            local_dofs.push(ld);
        }
        let n = dofs.len();
        let pattern = Arc::new(Pattern::new(n, &local_dofs));
        let solver = if direct {
            // AMD, not the geometric nested dissection: measured on the demo arch
            // (8,486 dofs) AMD fills 0.32M entries of L against 2.6M, and on the
            // small dam 0.09M against 0.23M (examples/factor_orderings.rs).
            let _ = &dof_xyz;
            let ordering = Ordering::Amd;
            // Thread start-up costs more than it saves on small systems (measured:
            // the demo's <= 7k-dof systems factor 1.7x faster on one thread).
            let par = if n < PARALLEL_FROM_DOFS {
                faer::Par::Seq
            } else {
                faer::Par::rayon(0)
            };
            Some(CholeskySolver::with_options(
                pattern.clone(),
                &ordering,
                par,
            )?)
        } else {
            None
        };

        let mut cap_lumped = vec![0.0; n];
        for (slot, &e) in live_elems.iter().enumerate() {
            for (k, &c) in data.cap_lumped[e as usize].iter().enumerate() {
                cap_lumped[local_dofs[slot][k] as usize] += c;
            }
        }
        let cap_consistent = if consistent {
            let mut m = SparseSym::new(pattern.clone());
            for (slot, &e) in live_elems.iter().enumerate() {
                m.add_element(slot, &data.cap_consistent[e as usize]);
            }
            Some(m)
        } else {
            None
        };
        let kh = SparseSym::new(pattern.clone());
        let mut sys = LiveSystem {
            dofs,
            index_of,
            elems: live_elems,
            local_dofs,
            exposed,
            pattern,
            cap_lumped,
            cap_consistent,
            kh,
            air_load: vec![0.0; n],
            fixed: vec![false; n],
            solver,
            factors: Vec::new(),
        };
        sys.assemble_kh(data, None)
            .expect("no faces are integrated without a film coefficient");
        Ok(sys)
    }

    pub fn n(&self) -> usize {
        self.dofs.len()
    }

    /// Reassembles K + H_air with the current exposed faces; air convection is
    /// dropped on faces whose four nodes are all submerged. Clears the factor cache.
    pub fn assemble_kh(
        &mut self,
        data: &ElementData,
        beta_day: Option<f64>,
    ) -> Result<(), ElementError> {
        let mut face_of_slot: HashMap<u32, Vec<u8>> = HashMap::new();
        if beta_day.is_some() {
            let slot_of: HashMap<u32, u32> = self
                .elems
                .iter()
                .enumerate()
                .map(|(s, &e)| (e, s as u32))
                .collect();
            for f in &self.exposed {
                face_of_slot
                    .entry(slot_of[&f.elem])
                    .or_default()
                    .push(f.face);
            }
        }
        self.kh.set_zero();
        self.air_load.iter_mut().for_each(|v| *v = 0.0);
        for (slot, &e) in self.elems.iter().enumerate() {
            let mut local: Mat8 = data.ke[e as usize];
            if let (Some(beta), Some(faces)) = (beta_day, face_of_slot.get(&(slot as u32))) {
                for &face in faces {
                    let ids = FACES[face as usize];
                    let ld = &self.local_dofs[slot];
                    if ids.iter().all(|&k| self.fixed[ld[k] as usize]) {
                        continue;
                    }
                    let (h, load) = data.face_convection(e as usize, face as usize, beta)?;
                    for a in 0..4 {
                        for b in 0..4 {
                            local[(ids[a], ids[b])] += h[(a, b)];
                        }
                        self.air_load[ld[ids[a]] as usize] += load[a];
                    }
                }
            }
            self.kh.add_element(slot, &local);
        }
        self.factors.clear();
        Ok(())
    }

    /// The factor of A = C + θΔt(K+H) with Dirichlet rows, from the cache or new.
    /// Returns the factor and whether it was computed now.
    pub fn factor(&mut self, dt: f64, theta: f64) -> Result<(&CholeskySolver, bool), SolveError> {
        let key = dt.to_bits() ^ theta.to_bits().rotate_left(17);
        if let Some(pos) = self.factors.iter().position(|(k, _)| *k == key) {
            return Ok((&self.factors[pos].1, false));
        }
        let mut a = SparseSym::new(self.pattern.clone());
        a.axpy(theta * dt, &self.kh);
        match &self.cap_consistent {
            Some(c) => a.axpy(1.0, c),
            None => {
                for (i, &c) in self.cap_lumped.iter().enumerate() {
                    a.add_diag(i, c);
                }
            }
        }
        a.apply_dirichlet(&self.fixed);
        let base = self.solver.as_ref().ok_or(SolveError::NotFactorized)?;
        let mut solver = base.fork()?;
        solver.factorize(&a)?;
        // A handful of step lengths recur (the step ladder); keep the last few.
        if self.factors.len() >= 6 {
            self.factors.remove(0);
        }
        self.factors.push((key, solver));
        Ok((&self.factors.last().expect("just pushed").1, true))
    }

    /// out = A v for A = C + θΔt(K+H) with Dirichlet rows and columns replaced
    /// by the identity (the matrix the direct path factorises).
    fn apply(
        &self,
        dt: f64,
        theta: f64,
        v: &[f64],
        out: &mut [f64],
        masked: &mut [f64],
        tmp: &mut [f64],
    ) {
        for i in 0..v.len() {
            masked[i] = if self.fixed[i] { 0.0 } else { v[i] };
        }
        self.cap_mul(masked, out);
        self.kh.mul_vec(masked, tmp);
        for i in 0..v.len() {
            out[i] = if self.fixed[i] {
                v[i]
            } else {
                out[i] + theta * dt * tmp[i]
            };
        }
    }

    /// Jacobi-preconditioned conjugate gradients on the system of
    /// [`LiveSystem::factor`]; `x` holds the initial guess (fixed entries must
    /// already equal `b`). Returns the iteration count, or the relative
    /// residual reached when `max_iter` is exhausted.
    pub fn solve_pcg(
        &self,
        dt: f64,
        theta: f64,
        b: &[f64],
        x: &mut [f64],
        tol: f64,
        max_iter: usize,
    ) -> Result<usize, f64> {
        let n = b.len();
        let kh_diag = self.kh.diag();
        let cap_diag = match &self.cap_consistent {
            Some(c) => c.diag(),
            None => self.cap_lumped.clone(),
        };
        let inv_diag: Vec<f64> = (0..n)
            .map(|i| {
                if self.fixed[i] {
                    0.0
                } else {
                    1.0 / (cap_diag[i] + theta * dt * kh_diag[i])
                }
            })
            .collect();
        let (mut masked, mut tmp, mut ap) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        self.apply(dt, theta, x, &mut ap, &mut masked, &mut tmp);
        let mut r: Vec<f64> = (0..n)
            .map(|i| if self.fixed[i] { 0.0 } else { b[i] - ap[i] })
            .collect();
        let b_norm = (0..n)
            .filter(|&i| !self.fixed[i])
            .map(|i| b[i] * b[i])
            .sum::<f64>()
            .sqrt();
        let target = tol * b_norm.max(f64::MIN_POSITIVE);
        let mut z: Vec<f64> = (0..n).map(|i| inv_diag[i] * r[i]).collect();
        let mut p = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        for it in 0..max_iter {
            let r_norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            if r_norm <= target {
                return Ok(it);
            }
            self.apply(dt, theta, &p, &mut ap, &mut masked, &mut tmp);
            for (v, &fixed) in ap.iter_mut().zip(&self.fixed) {
                if fixed {
                    *v = 0.0;
                }
            }
            let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
            let alpha = rz / pap;
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
                z[i] = inv_diag[i] * r[i];
            }
            let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        Err(r.iter().map(|v| v * v).sum::<f64>().sqrt() / b_norm.max(f64::MIN_POSITIVE))
    }

    /// y = C x
    pub fn cap_mul(&self, x: &[f64], y: &mut [f64]) {
        match &self.cap_consistent {
            Some(c) => c.mul_vec(x, y),
            None => {
                for ((yi, ci), xi) in y.iter_mut().zip(&self.cap_lumped).zip(x) {
                    *yi = ci * xi;
                }
            }
        }
    }
}
