//! The supports of one node as directions, and the nodal frame they define (theory §14.4): a
//! `[[dirichlet]]` component c holds u along e_c, a `normal` entry along n; the frame's first
//! rows span the held directions, its last rows the free ones, so that in it an inclined
//! support is an ordinary fixed component.

/// Directions closer than this (the sine of their angle, or of the angle to the span of the
/// previous ones) count as dependent: the later one adds no constraint. Normals are given as
/// data, so a dependent one is an exact repetition (the same plane twice, a plane and a clamp)
/// and its residual is round-off (≤ 1e-16); an independent one in a real mesh is at least
/// degrees away.
const DEPENDENT: f64 = 1e-10;

/// The supports at one node (theory §14.4): up to three independent unit directions along
/// which u is held, in the order of the `[[dirichlet]]` entries, each with the entry holding it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodalSupport {
    /// Number of directions.
    pub n: u8,
    /// The entry of each direction.
    pub entry: [u32; 3],
    /// The directions (unit).
    pub direction: [[f64; 3]; 3],
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let s = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let a = a.map(|x| x / s);
    let n = dot(&a, &a).sqrt();
    a.map(|x| x / n)
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

impl NodalSupport {
    /// The held directions with their entries.
    pub fn directions(&self) -> impl Iterator<Item = (u32, [f64; 3])> + '_ {
        (0..self.n as usize).map(|i| (self.entry[i], self.direction[i]))
    }

    /// The orthonormal basis of the held span (Gram–Schmidt in entry order).
    fn orthonormal(&self) -> Vec<[f64; 3]> {
        let mut q: Vec<[f64; 3]> = Vec::with_capacity(3);
        for (_, d) in self.directions() {
            q.push(unit(residual(&q, d)));
        }
        q
    }

    /// Holds u along `d` (not zero) for `entry`, unless `d` is in the span already held.
    pub fn hold(&mut self, entry: u32, d: [f64; 3]) {
        let d = unit(d);
        let r = residual(&self.orthonormal(), d);
        if self.n < 3 && dot(&r, &r).sqrt() > DEPENDENT {
            self.entry[self.n as usize] = entry;
            self.direction[self.n as usize] = d;
            self.n += 1;
        }
    }

    /// The components held when every direction is a coordinate axis (±e_c): then the node
    /// needs no frame. `None` when some direction is inclined.
    pub fn axes(&self) -> Option<[bool; 3]> {
        let mut fixed = [false; 3];
        for (_, d) in self.directions() {
            let c = (0..3).find(|&c| d[c].abs() == 1.0)?;
            fixed[c] = true;
        }
        Some(fixed)
    }

    /// The nodal frame R (rows orthonormal, right-handed): rows 0..n span the held directions,
    /// the others the free ones; local component k of u is R[k]·u.
    pub fn frame(&self) -> [[f64; 3]; 3] {
        let mut q = self.orthonormal();
        if q.is_empty() {
            q.push([1.0, 0.0, 0.0]);
        }
        if q.len() == 1 {
            // the axis least along q[0], made orthogonal to it
            let c = (0..3).min_by(|&a, &b| q[0][a].abs().total_cmp(&q[0][b].abs())).unwrap_or(0);
            let mut e = [0.0; 3];
            e[c] = 1.0;
            q.push(unit(residual(&q, e)));
        }
        [q[0], q[1], cross(&q[0], &q[1])]
    }

    /// α with r = Σ αᵢ dᵢ over the held directions dᵢ: the least-squares split of a nodal force
    /// onto them (its part along the free directions, an equilibrium residual, is dropped).
    pub fn split(&self, r: [f64; 3]) -> [f64; 3] {
        self.gram_solve(std::array::from_fn(|i| dot(&self.direction[i], &r)))
    }

    /// The least-norm displacement u with dᵢ·u = vᵢ for every held direction: Σ αᵢ dᵢ with
    /// Gα = v (G the Gram matrix of the dᵢ); on the axes, vᵢ along each.
    pub fn lift(&self, v: [f64; 3]) -> [f64; 3] {
        let a = self.gram_solve(v);
        std::array::from_fn(|c| (0..self.n as usize).map(|i| a[i] * self.direction[i][c]).sum())
    }

    /// G⁻¹ b on the held directions (the other entries 0).
    fn gram_solve(&self, b: [f64; 3]) -> [f64; 3] {
        let n = self.n as usize;
        let d = &self.direction;
        let gram =
            nalgebra::Matrix3::from_fn(|i, j| if i < n && j < n { dot(&d[i], &d[j]) } else { (i == j) as u8 as f64 });
        let rhs = nalgebra::Vector3::from_fn(|i, _| if i < n { b[i] } else { 0.0 });
        let a = gram.cholesky().map_or(nalgebra::Vector3::zeros(), |c| c.solve(&rhs));
        [a[0], a[1], a[2]]
    }
}

/// d minus its projection on the orthonormal vectors `q`.
fn residual(q: &[[f64; 3]], mut d: [f64; 3]) -> [f64; 3] {
    for qi in q {
        let s = dot(qi, &d);
        for c in 0..3 {
            d[c] -= s * qi[c];
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dependent_directions_add_nothing_and_the_frame_is_orthonormal() {
        let (s, c) = (0.5_f64, 3.0_f64.sqrt() / 2.0);
        let mut a = NodalSupport::default();
        a.hold(0, [s, 0.0, c]);
        a.hold(1, [-2.0 * s, 0.0, -2.0 * c]); // the same plane: dropped
        assert_eq!(a.n, 1);
        assert!(a.axes().is_none());
        a.hold(2, [0.0, 1.0, 0.0]);
        assert_eq!((a.n, a.entry[1]), (2, 2));
        let r = a.frame();
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(&r[i], &r[j]) - want).abs() < 1e-15, "{r:?}");
            }
        }
        // the free direction is orthogonal to both held ones
        assert!(dot(&r[2], &[s, 0.0, c]).abs() < 1e-15 && r[2][1].abs() < 1e-15);
        // a force along the held directions splits back into them
        let f: [f64; 3] = std::array::from_fn(|k| 2.0 * [s, 0.0, c][k] - 3.0 * [0.0, 1.0, 0.0][k]);
        let alpha = a.split(f);
        assert!((alpha[0] - 2.0).abs() < 1e-15 && (alpha[1] + 3.0).abs() < 1e-15, "{alpha:?}");
        // the lifting meets both prescribed values
        let u = a.lift([0.25, -0.5, 0.0]);
        assert!((dot(&u, &[s, 0.0, c]) - 0.25).abs() < 1e-15 && (u[1] + 0.5).abs() < 1e-15, "{u:?}");
        // the axes need no frame
        let mut b = NodalSupport::default();
        b.hold(0, [0.0, 0.0, -3.0]);
        b.hold(1, [1.0, 0.0, 0.0]);
        assert_eq!(b.axes(), Some([true, false, true]));
    }
}
