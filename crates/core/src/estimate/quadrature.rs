//! The rule the error indicators are integrated with (theory §15.1): the four-point Gauss rule
//! of degree 2 on each of the eight children of one red refinement of the element, 32 points of
//! equal positive weight. It integrates the squared difference of a P1 recovery and P0 stresses
//! (a quadratic) exactly; for a P2 recovery (a quartic) it is a degree-2 rule on children of half
//! the size.

/// Barycentric coordinates of the four Gauss points of a tetrahedron: `A` at vertex q, `B` at
/// the others.
const A: f64 = 0.585_410_196_624_968_5;
const B: f64 = 0.138_196_601_125_010_5;

/// Number of points of the rule.
pub const POINTS: usize = 32;

/// The eight children of the red refinement, as corners in barycentric coordinates of the
/// parent: four corner tetrahedra and the octahedron cut along the diagonal between the
/// midpoints of edges (0, 2) and (1, 3). All have a volume of 1/8 of the parent's.
fn children() -> [[[f64; 4]; 4]; 8] {
    let v = |a: usize| -> [f64; 4] { std::array::from_fn(|k| (k == a) as u8 as f64) };
    let m =
        |a: usize, b: usize| -> [f64; 4] { std::array::from_fn(|k| 0.5 * ((k == a) as u8 + (k == b) as u8) as f64) };
    let (m01, m02, m03, m12, m13, m23) = (m(0, 1), m(0, 2), m(0, 3), m(1, 2), m(1, 3), m(2, 3));
    [
        [v(0), m01, m02, m03],
        [m01, v(1), m12, m13],
        [m02, m12, v(2), m23],
        [m03, m13, m23, v(3)],
        // the octahedron m01 m02 m03 m12 m13 m23, around its diagonal m02–m13
        [m02, m13, m01, m03],
        [m02, m13, m03, m23],
        [m02, m13, m23, m12],
        [m02, m13, m12, m01],
    ]
}

/// The points of the rule in barycentric coordinates of the element; every weight is 1/32 of
/// the element's volume.
pub fn points() -> [[f64; 4]; POINTS] {
    let kids = children();
    std::array::from_fn(|i| {
        let (c, q) = (&kids[i / 4], i % 4);
        std::array::from_fn(|k| (0..4).map(|a| if a == q { A } else { B } * c[a][k]).sum())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_T λ_0^a λ_1^b λ_2^c λ_3^d = a! b! c! d! 3! / (a + b + c + d + 3)! |T|: the rule is exact
    /// for quadratics (and the children tile the element: their volumes are 1/8 each).
    #[test]
    fn the_rule_integrates_quadratics_exactly() {
        let fact = |n: u32| (1..=n).product::<u32>() as f64;
        let exact = |e: [u32; 4]| e.iter().map(|&k| fact(k)).product::<f64>() * 6.0 / fact(e.iter().sum::<u32>() + 3);
        for e in [[0, 0, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [2, 0, 0, 0], [1, 1, 0, 0], [0, 1, 0, 1], [0, 0, 1, 1]] {
            let rule: f64 =
                points().iter().map(|p| (0..4).map(|k| p[k].powi(e[k] as i32)).product::<f64>()).sum::<f64>()
                    / POINTS as f64;
            assert!((rule - exact(e)).abs() < 1e-15, "{e:?}: {rule} against {}", exact(e));
        }
        // a quartic is integrated only approximately, but close (λ_0⁴: 4!·3!/7! = 1/35)
        let q: f64 = points().iter().map(|p| p[0].powi(4)).sum::<f64>() / POINTS as f64;
        assert!((q - 1.0 / 35.0).abs() < 0.02 / 35.0, "{q}");
        for c in children() {
            let d = |k: usize| -> [f64; 3] { std::array::from_fn(|i| c[k][i + 1] - c[0][i + 1]) };
            let (a, b, cc) = (d(1), d(2), d(3));
            let det = a[0] * (b[1] * cc[2] - b[2] * cc[1]) - a[1] * (b[0] * cc[2] - b[2] * cc[0])
                + a[2] * (b[0] * cc[1] - b[1] * cc[0]);
            assert!((det.abs() - 0.125).abs() < 1e-15, "child {c:?}: volume fraction {}", det.abs());
        }
    }
}
