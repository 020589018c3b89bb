//! Automatic step cutting (theory §11.5): a load step that fails is retried with half the
//! increment, up to `max_cuts` times per planned step and never below `min_step`; the solved
//! sub-steps then go on to the planned factor with the increment that worked.

use serde::{Deserialize, Serialize};

/// The settings of step cutting (`[load_path]` fields `max_cuts`, `min_step`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepCutting {
    /// Halvings of the increment per planned step (0: a failed step stops the path at once).
    pub max_cuts: usize,
    /// No increment of the load factor below this is tried.
    pub min_step: f64,
}

/// Five halvings (a step cut to 1/32) reach the loads at which Newton converges on every path
/// measured (theory §11.5); the floor 1e-6 keeps a path that cannot go on from creeping.
impl Default for StepCutting {
    fn default() -> Self {
        Self { max_cuts: 5, min_step: 1e-6 }
    }
}

/// The way from the last solved factor to the next planned one, in sub-steps (theory §11.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Increment {
    from: f64,
    to: f64,
    step: f64,
    cuts: usize,
    reached: bool,
}

impl Increment {
    /// From the factor solved last, `from`, to the planned `to`, in one step.
    pub fn new(from: f64, to: f64) -> Self {
        Self { from, to, step: (to - from).abs(), cuts: 0, reached: false }
    }

    /// The factor to try next (`to` itself when it is `from`: a step that holds the load);
    /// `None` once `to` is solved.
    pub fn next(&self) -> Option<f64> {
        let left = self.to - self.from;
        if self.reached {
            None
        } else if left.abs() <= self.step {
            Some(self.to)
        } else {
            Some(self.from + self.step.copysign(left))
        }
    }

    /// The step to `factor` converged: the next starts there.
    pub fn solved(&mut self, factor: f64) {
        self.from = factor;
        self.reached = factor == self.to;
    }

    /// The factor solved last.
    pub fn from(&self) -> f64 {
        self.from
    }

    /// The step tried failed: halves the increment when `settings` allow it (fewer than
    /// `max_cuts` halvings so far and half the increment at least `min_step`); true when cut.
    pub fn cut(&mut self, settings: &StepCutting) -> bool {
        let half = 0.5 * self.step;
        let allowed = self.cuts < settings.max_cuts && half >= settings.min_step;
        if allowed {
            self.step = half;
            self.cuts += 1;
        }
        allowed
    }

    /// The increment tried (the smallest so far: it only shrinks).
    pub fn step(&self) -> f64 {
        self.step
    }

    /// Halvings so far.
    pub fn cuts(&self) -> usize {
        self.cuts
    }
}

#[cfg(test)]
mod tests {
    use super::{Increment, StepCutting};

    #[test]
    fn a_failed_step_is_halved_and_the_rest_goes_on_with_the_half() {
        let s = StepCutting { max_cuts: 2, min_step: 1e-3 };
        let mut inc = Increment::new(1.0, 0.0);
        assert_eq!(inc.next(), Some(0.0));
        assert!(inc.cut(&s));
        assert_eq!(inc.next(), Some(0.5));
        inc.solved(0.5);
        assert_eq!(inc.next(), Some(0.0));
        assert!(inc.cut(&s));
        assert_eq!(inc.next(), Some(0.25));
        assert!(!inc.cut(&s), "max_cuts = 2");
        assert_eq!((inc.step(), inc.cuts()), (0.25, 2));
        inc.solved(0.25);
        inc.solved(0.0);
        assert_eq!(inc.next(), None);
        let mut tiny = Increment::new(0.0, 1.5e-3);
        assert!(!tiny.cut(&s), "half the step is below min_step");
        let mut hold = Increment::new(1.0, 1.0);
        assert_eq!(hold.next(), Some(1.0), "a step at the same load is solved");
        hold.solved(1.0);
        assert_eq!(hold.next(), None);
        assert!(!Increment::new(0.0, 1.0).cut(&StepCutting { max_cuts: 0, min_step: 1e-6 }));
    }
}
