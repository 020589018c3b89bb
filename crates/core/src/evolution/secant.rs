//! The secant predictor of a ladder of stationary problems (theory §11.2): the start of the
//! solve at load factor f extrapolated linearly from the last two solutions, the zero solution
//! at factor 0 standing in for the first (Allgower & Georg, *Introduction to Numerical
//! Continuation Methods*, 1990, §2.2). Exact when the solution is linear in the load (an
//! elastic body); an iterate, never an answer, where it is not.

use crate::Start;

/// The solutions at the last two factors of a ladder, and the start they predict.
#[derive(Debug, Default)]
pub struct SecantPredictor {
    /// (factor, solution) of the point before the last; `None`: the zero solution at 0.
    before: Option<(f64, Start)>,
    /// (factor, solution) of the last converged point.
    last: Option<(f64, Start)>,
}

impl SecantPredictor {
    /// A converged solution at `factor`.
    pub fn record(&mut self, factor: f64, solution: Start) {
        self.before = self.last.replace((factor, solution));
    }

    /// The start at `factor`: x_last + (f − f_last)/(f_last − f_before)·(x_last − x_before) for
    /// u, V and λ (λ of a normal row kept ≥ 0 is the solver's business: a start is only an
    /// iterate). The last solution itself when the two factors coincide; `None` before any.
    pub fn predict(&self, factor: f64) -> Option<Start> {
        let (f1, x1) = self.last.as_ref()?;
        let (f0, x0) = match &self.before {
            Some((f, x)) => (*f, Some(x)),
            None => (0.0, None),
        };
        if f1 == &f0 {
            return Some(x1.clone());
        }
        let t = (factor - f1) / (f1 - f0);
        let line = |a: &[f64], b: Option<&Vec<f64>>| -> Vec<f64> {
            match b {
                Some(b) => a.iter().zip(b).map(|(a, b)| a + t * (a - b)).collect(),
                None => a.iter().map(|a| a * (1.0 + t)).collect(),
            }
        };
        Some(Start {
            u: line(&x1.u, x0.map(|x| &x.u)),
            extras: line(&x1.extras, x0.map(|x| &x.extras)),
            lambda: line(&x1.lambda, x0.map(|x| &x.lambda)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start(s: f64) -> Start {
        Start { u: vec![s, -2.0 * s], extras: vec![3.0 * s], lambda: vec![0.5 * s] }
    }

    #[test]
    fn a_solution_linear_in_the_factor_is_predicted_exactly() {
        let mut p = SecantPredictor::default();
        assert!(p.predict(1.0).is_none());
        p.record(2.0, start(2.0));
        // from the zero solution at 0 and the one at 2: the scaling by f/2
        assert_eq!(p.predict(5.0).unwrap().u, start(5.0).u);
        p.record(5.0, start(5.0));
        let q = p.predict(11.0).unwrap();
        assert_eq!((q.u, q.extras, q.lambda), (start(11.0).u, start(11.0).extras, start(11.0).lambda));
    }

    #[test]
    fn a_curved_path_is_extrapolated_along_its_last_chord() {
        // x(f) = f²: points at 1 and 2, predicted at 4: 4 + 2·(4 − 1) = 10 (the chord's line)
        let mut p = SecantPredictor::default();
        let sq = |f: f64| Start { u: vec![f * f], extras: vec![], lambda: vec![] };
        p.record(1.0, sq(1.0));
        p.record(2.0, sq(2.0));
        assert!((p.predict(4.0).unwrap().u[0] - 10.0).abs() < 1e-15);
    }
}
