//! The conformance kit catches broken plugins, each with the check that names the flaw, and
//! accepts a correct plugin with two extra unknowns whose balancing needs the QP fallback.

mod common;

use common::*;
use saddle_contact::conformance::{self, CHECKS, check_all};
use saddle_contact::{Paraboloid, RigidPunch, zone};
use saddle_core::{
    AdmissibleDisplacements, ConstraintRows, ContactReport, DofMap, ParameterError, Region, SceneError, TetMesh,
    contact_set,
};
use serde::{Deserialize, Serialize};

/// What is wrong with a [`Broken`] punch.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
enum Flaw {
    /// Offsets 0 instead of φ(x_i).
    OffsetNotPhi,
    /// H = +1: g = u₃ + φ + U.
    HWrongSign,
    /// gap() reads u₁ instead of u₃.
    GapReadsX,
    /// gap() curved (−50 u₃²) while the rows are its linearisation: second-order consistent,
    /// but the projection onto the rows is not feasible for gap().
    CurvedGap,
    /// An extra row with no entries at all.
    ZeroRow,
    /// A NaN offset.
    NanOffset,
    /// Rows with one H column, extra_names() empty.
    NamesMismatch,
    /// load() empty for the extra U.
    LoadMissing,
    /// load() = [NaN].
    LoadNan,
    /// Reports half of Σλ as the force.
    ForceHalved,
    /// Reports U = 0 whatever the extras.
    WrongU,
    /// Counts one contact node too many.
    ContactCount,
    /// scaled_load ignores the factor.
    ScaleIgnored,
}

/// A rigid punch with one deliberate flaw.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Broken {
    punch: RigidPunch,
    flaw: Flaw,
}

#[typetag::serde(name = "test_broken_punch")]
impl AdmissibleDisplacements for Broken {
    fn validate(&self, path: &str) -> Result<(), ParameterError> {
        self.punch.validate(path)
    }

    fn extra_names(&self) -> Vec<String> {
        if self.flaw == Flaw::NamesMismatch { vec![] } else { self.punch.extra_names() }
    }

    fn load(&self) -> Vec<f64> {
        match self.flaw {
            Flaw::LoadMissing => vec![],
            Flaw::LoadNan => vec![f64::NAN],
            _ => self.punch.load(),
        }
    }

    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let mut rows = self.punch.discretise(mesh, dofs, path)?;
        match self.flaw {
            Flaw::OffsetNotPhi => rows.offset.iter_mut().for_each(|c| *c = 0.0),
            Flaw::HWrongSign => rows.extra.iter_mut().for_each(|h| *h = -*h),
            Flaw::ZeroRow => rows.push(&[], &[0.0], 0.1, rows.node[0]),
            Flaw::NanOffset => rows.offset[3] = f64::NAN,
            _ => {}
        }
        Ok(rows)
    }

    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        self.punch.gap(mesh, dofs, rows, u, extras, out);
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let at = |c| dofs.free(n, c).map_or(0.0, |j| u[j]);
            match self.flaw {
                Flaw::GapReadsX => *g += at(0) - at(2),
                Flaw::CurvedGap => *g -= 50.0 * at(2) * at(2),
                _ => {}
            }
        }
    }

    fn scaled_load(&self, factor: f64) -> Option<Box<dyn AdmissibleDisplacements>> {
        let factor = if self.flaw == Flaw::ScaleIgnored { 1.0 } else { factor };
        Some(Box::new(Broken { punch: RigidPunch { F: self.punch.F * factor, ..self.punch.clone() }, flaw: self.flaw }))
    }

    fn report(&self, mesh: &TetMesh, rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        let mut r = self.punch.report(mesh, rows, extras, lambda);
        match self.flaw {
            Flaw::ForceHalved => r.quantities[1].1 *= 0.5,
            Flaw::WrongU => r.quantities[0].1 = 0.0,
            Flaw::ContactCount => r.contact_nodes += 1,
            _ => {}
        }
        r
    }
}

fn broken(flaw: Flaw) -> Broken {
    Broken { punch: RigidPunch::new(0.3, disc(0.5), Box::new(Paraboloid::new(5.0))).unwrap(), flaw }
}

#[test]
fn every_flaw_is_caught_by_its_check() {
    let m = mesh();
    let d = dofs(&m);
    let expected = [
        (Flaw::OffsetNotPhi, "gap_value"),
        (Flaw::HWrongSign, "gap_derivative"),
        (Flaw::GapReadsX, "gap_derivative"),
        (Flaw::CurvedGap, "projection_feasible"),
        (Flaw::ZeroRow, "rows"),
        (Flaw::NanOffset, "rows"),
        (Flaw::NamesMismatch, "rows"),
        (Flaw::LoadMissing, "load"),
        (Flaw::LoadNan, "load"),
        (Flaw::ForceHalved, "force"),
        (Flaw::WrongU, "report"),
        (Flaw::ContactCount, "report"),
        (Flaw::ScaleIgnored, "scaled_load"),
    ];
    for (flaw, check) in expected {
        assert!(CHECKS.contains(&check));
        for seed in [1, 2] {
            let e = check_all(&broken(flaw), &m, &d, seed, 0.01).expect_err(&format!("{flaw:?} passed the kit"));
            assert_eq!(e.check, check, "{flaw:?}: {e}");
            assert!(e.to_string().starts_with(&format!("conformance check `{check}` failed: ")), "{e}");
        }
    }
}

#[test]
fn failure_messages_carry_the_numbers() {
    let m = mesh();
    let d = dofs(&m);
    let e = check_all(&broken(Flaw::ForceHalved), &m, &d, 3, 0.01).unwrap_err();
    // balanced multipliers sum to F = 0.3; the broken report halves that
    assert!(e.message.contains("force = 1.500000000000e-1"), "{e}");
    assert!(e.message.contains("Σλ = 3.0000000000") || e.message.contains("Σλ = 2.9999999999"), "{e}");
    let e = check_all(&broken(Flaw::OffsetNotPhi), &m, &d, 3, 0.01).unwrap_err();
    // the first row whose offset differs most from φ: the rim nodes at distance 0.5, φ = 0.025
    assert!(e.message.contains("the offset c = 0.000000e0 but gap() = 2.500000e-2"), "{e}");
    let e = check_all(&broken(Flaw::NanOffset), &m, &d, 3, 0.01).unwrap_err();
    assert!(e.message.starts_with("row 3 ") && e.message.contains("c = NaN"), "{e}");
    let e = check_all(&broken(Flaw::ZeroRow), &m, &d, 3, 0.01).unwrap_err();
    assert!(e.message.starts_with("row 13 ") && e.message.contains("c = 0.1"), "{e}");
    let e = check_all(&broken(Flaw::HWrongSign), &m, &d, 3, 0.01).unwrap_err();
    // FD of gap() along dV gives −dV, the rows +dV: the message says ∂g/∂V and both numbers
    assert!(e.message.starts_with("∂g/∂V"), "{e}");
}

#[test]
fn the_individual_checks_run_alone() {
    let m = mesh();
    let d = dofs(&m);
    assert_eq!(
        conformance::check_projection(&broken(Flaw::CurvedGap), &m, &d, 4, 0.01).unwrap_err().check,
        "projection_feasible"
    );
    conformance::check_linearisation(&broken(Flaw::CurvedGap), &m, &d, 4, 0.01).unwrap();
    conformance::check_load(&broken(Flaw::CurvedGap), &m, &d, 4, 0.01).unwrap();
    assert_eq!(conformance::check_load(&broken(Flaw::WrongU), &m, &d, 4, 0.01).unwrap_err().check, "report");
    conformance::check_linearisation(&broken(Flaw::WrongU), &m, &d, 4, 0.01).unwrap();
    assert_eq!(conformance::check_rows(&broken(Flaw::ZeroRow), &m, &d, 4, 0.01).unwrap_err().check, "rows");
    let e = check_all(&broken(Flaw::WrongU), &m, &d, 4, f64::NAN).unwrap_err();
    assert_eq!(e.check, "setup");
    let bad = Broken {
        punch: RigidPunch {
            F: -1.0,
            zone: disc(0.5),
            gap: Box::new(Paraboloid::new(5.0)),
            friction: None,
            Q: None,
            W: None,
        },
        flaw: Flaw::WrongU,
    };
    assert_eq!(check_all(&bad, &m, &d, 4, 0.01).unwrap_err().check, "validate");
    let far = Region::All(vec![Region::Group("zmin".into()), Region::Disc { center: [5.0, 5.0], radius: 0.5 }]);
    let bad = Broken { punch: RigidPunch::new(0.3, far, Box::new(Paraboloid::new(5.0))).unwrap(), flaw: Flaw::WrongU };
    let e = check_all(&bad, &m, &d, 4, 0.01).unwrap_err();
    assert_eq!(e.check, "discretise");
    assert!(e.message.contains("obstacle.zone"), "{e}");
}

/// A punch that can also tilt about the x₂ axis: g_i = u₃ + φ − U − θ x₁, loaded by a force F
/// and a moment M (H rows [−1, −x₁]; balance Σλ = F, Σλ x₁ = M).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct TiltingPunch {
    force: f64,
    moment: f64,
    zone: Region,
}

#[typetag::serde(name = "test_tilting_punch")]
impl AdmissibleDisplacements for TiltingPunch {
    fn validate(&self, _path: &str) -> Result<(), ParameterError> {
        Ok(())
    }

    fn extra_names(&self) -> Vec<String> {
        vec!["U".into(), "theta".into()]
    }

    fn load(&self) -> Vec<f64> {
        vec![self.force, self.moment]
    }

    fn discretise(&self, mesh: &TetMesh, dofs: &DofMap, path: &str) -> Result<ConstraintRows, SceneError> {
        let nodes = zone::candidate_nodes(&self.zone, mesh, dofs, path)?;
        let mut rows = ConstraintRows::new(2);
        for &n in &nodes.nodes {
            let x = mesh.nodes[n];
            rows.push(&[(dofs.free(n, 2).unwrap(), 1.0)], &[-1.0, -x[0]], (x[0] * x[0] + x[1] * x[1]) / 10.0, n);
        }
        Ok(rows)
    }

    fn gap(&self, mesh: &TetMesh, dofs: &DofMap, rows: &ConstraintRows, u: &[f64], extras: &[f64], out: &mut [f64]) {
        for (g, &n) in out.iter_mut().zip(&rows.node) {
            let x = mesh.nodes[n];
            *g = dofs.free(n, 2).map_or(0.0, |j| u[j]) + (x[0] * x[0] + x[1] * x[1]) / 10.0
                - extras[0]
                - extras[1] * x[0];
        }
    }

    fn report(&self, _mesh: &TetMesh, _rows: &ConstraintRows, extras: &[f64], lambda: &[f64]) -> ContactReport {
        ContactReport {
            quantities: vec![
                ("U".into(), extras[0]),
                ("theta".into(), extras[1]),
                ("force".into(), lambda.iter().sum()),
            ],
            contact_nodes: contact_set(lambda).len(),
            ..Default::default()
        }
    }
}

#[test]
fn two_extras_balanced_by_the_fallback_and_an_unbalanceable_moment() {
    let m = mesh();
    let d = dofs(&m);
    let tilting = |moment| TiltingPunch { force: 0.3, moment, zone: disc(0.5) };
    // the least-norm multipliers λ = H(HᵀH)⁻¹(−f) are affine in x₁: a + b x₁ with
    // a = F/13, b = M/Σx₁² (Σx₁ = 0 over the 13 nodes, Σx₁² = 6·0.0625 + 2·0.25 = 0.875);
    // for M = 0.4 F they are negative at x₁ = −0.5, so the kit's exact QP cannot start there
    let (a, b) = (0.3 / 13.0, 0.4 * 0.3 / 0.875);
    assert!(a - 0.5 * b < 0.0);
    for seed in [1, 2, 3] {
        check_all(&tilting(0.4 * 0.3), &m, &d, seed, 0.01).unwrap();
    }
    check_all(&tilting(0.0), &m, &d, 1, 0.01).unwrap();
    // the resultant must act inside the zone: |M/F| ≤ max |x₁| = 0.5
    let e = check_all(&tilting(0.6 * 0.3), &m, &d, 1, 0.01).unwrap_err();
    assert_eq!(e.check, "load", "{e}");
    assert!(e.message.contains("no multipliers λ ≥ 0 balance the load f = [0.3, 0.18"), "{e}");
}
