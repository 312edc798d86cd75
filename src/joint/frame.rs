//! Local contact frames (t1, t2, n) built from a joint normal.
//!
//! The frame is right-handed and orthonormal: t1 × t2 = n. For the usual
//! transverse joint (normal roughly horizontal, along the dam axis) t1 is
//! horizontal and t2 points upward-ish along the dip of the joint, so with
//! n = +x (ARCHITECTURE axes: x along the axis, y downstream, z up) the frame
//! is t1 = +y (downstream), t2 = +z (up). For a nearly vertical normal
//! (|n_z| > 0.9) the reference axis switches from e_z to e_x, so the frame
//! never degenerates.

use super::contact::ContactError;

/// Orthonormal right-handed contact frame: `t1 × t2 = n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    /// First tangent (horizontal for a non-vertical normal).
    pub t1: [f64; 3],
    /// Second tangent, `n × t1`.
    pub t2: [f64; 3],
    /// Unit normal, from side A to side B.
    pub n: [f64; 3],
}

impl LocalFrame {
    /// Builds the frame of a normal of any non-zero length (it is normalised).
    /// Errors on a zero or non-finite normal.
    pub fn from_normal(normal: [f64; 3]) -> Result<Self, ContactError> {
        let len = norm3(normal);
        if !len.is_finite() || len <= f64::MIN_POSITIVE {
            return Err(ContactError::Invalid(format!(
                "contact normal must be finite and non-zero, got {normal:?}"
            )));
        }
        let n = [normal[0] / len, normal[1] / len, normal[2] / len];
        let reference = if n[2].abs() <= 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let a = cross3(reference, n);
        let la = norm3(a);
        // |a| ≥ sqrt(1 − 0.9²) ≈ 0.436 by the choice of the reference axis.
        let t1 = [a[0] / la, a[1] / la, a[2] / la];
        let t2 = cross3(n, t1);
        Ok(Self { t1, t2, n })
    }

    /// Components (t1, t2, n) of a global vector.
    pub fn to_local(&self, v: [f64; 3]) -> [f64; 3] {
        [dot3(self.t1, v), dot3(self.t2, v), dot3(self.n, v)]
    }

    /// Global vector from local components (t1, t2, n).
    pub fn to_global(&self, l: [f64; 3]) -> [f64; 3] {
        let mut g = [0.0; 3];
        for (k, gk) in g.iter_mut().enumerate() {
            *gk = self.t1[k] * l[0] + self.t2[k] * l[1] + self.n[k] * l[2];
        }
        g
    }

    /// Rows t1, t2, n: the rotation global → local (`local = R · global`).
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        [self.t1, self.t2, self.n]
    }
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm3(a: [f64; 3]) -> f64 {
    dot3(a, a).sqrt()
}
