//! The forcing terms of inexact Newton (theory §4.2, linear backends): the relative residual
//! η_k to which the k-th Newton system is solved by CG.
//!
//! * `residual`: η_k = η_max · min(r_k, 1), r_k the relative KKT residual of the iterate.
//! * `eisenstat_walker` (Eisenstat & Walker 1996, SIAM J. Sci. Comput. 17(1), choice 2 with
//!   γ = 0.9, α = 2): η_k = γ (r_k / r_{k−1})², raised to γ η_{k−1}² when that exceeds 0.1 (so
//!   that η does not fall abruptly after a single good step), capped at η_max, and not below
//!   `OVERSOLVE_MARGIN · tol / r_k` (Kelley 1995, §6.3: a solve more accurate than the step to
//!   `tol` needs is wasted). Far from the solution, where r falls slowly (active and plastic
//!   sets still changing), η stays at η_max; in the quadratic phase it follows r², as the
//!   residual rule does, but without the oversolving of the last step.
//!
//! Under either rule, while r_k > `slow` · r_{k−1} (Newton's `slow_contraction`: the residual
//! falls slowly, its active or plastic sets still changing) η_k = η_max: the outer residual is
//! then limited by the sets, not by the linear solve, and the tighter term of the residual rule
//! would be wasted. Once r falls faster the rule applies, so the last steps are solved as before.
//!
//! In the fast phase, a step that the quadratic model r_{k+1} ≈ r_k (r_k/r_{k−1})² does not
//! expect to be the last (the model above `last_margin` · `tol`, Newton's `last_step_margin`)
//! stops at Eisenstat–Walker's γ (r_k/r_{k−1})² when that is looser than the rule's term: the
//! linear error then matches the error the outer step leaves anyway. The step the model expects
//! to be the last keeps the rule's term, so the final digits are those of the rule.
//!
//! Either way the outer iteration stops on the KKT residual of theory §3.4, so the answer is the
//! same to Newton's `tol`; only the CG iterations spent on the way differ.

use serde::{Deserialize, Serialize};

/// `forcing = "residual" | "eisenstat_walker"`: how the CG tolerance follows Newton's progress.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForcingRule {
    /// η_k = η_max · min(r_k, 1) (the default).
    #[default]
    Residual,
    /// Eisenstat–Walker's choice 2 with the safeguards of the module docs.
    EisenstatWalker,
}

/// γ of Eisenstat–Walker's choice 2.
pub const EW_GAMMA: f64 = 0.9;
/// α of Eisenstat–Walker's choice 2.
pub const EW_ALPHA: f64 = 2.0;
/// The safeguard threshold of Eisenstat–Walker: γ η_{k−1}^α above it bounds η_k from below.
pub const EW_SAFEGUARD: f64 = 0.1;
/// η_k ≥ this · tol / r_k: the step's solve need not be more accurate than what takes the
/// residual to a tenth of `tol` (the margin covers the 2-norm of CG against the KKT residual's
/// scaling; a step that lands above `tol` costs a whole Newton step more).
pub const OVERSOLVE_MARGIN: f64 = 0.1;
/// The default of Newton's `slow_contraction`: a residual that falls by less than 10× in a step
/// is not in Newton's fast phase (on the P1 default scene the plastic steps contract by 0.37 and
/// 0.22 while the active and plastic sets settle, then by 0.026, 3.5e-3 and 1.2e-6).
pub const SLOW_CONTRACTION: f64 = 0.1;
/// The default of Newton's `last_step_margin`: a fast step whose quadratic model of the next
/// residual is within 100 × `tol` may be the last and keeps the rule's term.
pub const LAST_STEP_MARGIN: f64 = 100.0;

/// The forcing terms of one Newton solve: the rule and what it remembers of the last step.
#[derive(Clone, Debug)]
pub struct ForcingTerms {
    rule: ForcingRule,
    /// η_max (Newton's `cg_forcing`).
    max: f64,
    /// Newton's `tol`.
    tol: f64,
    /// (r, η) of the last step.
    last: Option<(f64, f64)>,
    /// η = η_max while r_k > `slow` · r_{k−1} (0: never).
    slow: f64,
    /// A fast step whose quadratic model lies above this multiple of `tol` is not the last
    /// (0: the rule in every fast step).
    last_margin: f64,
}

impl ForcingTerms {
    /// The forcing terms of `rule` with η_max = `max` for a Newton solve to `tol`.
    pub fn new(rule: ForcingRule, max: f64, tol: f64) -> Self {
        Self { rule, max, tol, last: None, slow: 0.0, last_margin: 0.0 }
    }

    /// The same, with Eisenstat–Walker's term in the fast steps whose quadratic model of the
    /// next residual lies above `last_margin` · `tol`.
    pub fn relaxed_before_the_last(self, last_margin: f64) -> Self {
        Self { last_margin, ..self }
    }

    /// The same, with η = η_max while the residual contracts by less than `slow` per step.
    pub fn slow_below(self, slow: f64) -> Self {
        Self { slow, ..self }
    }

    /// η for the step from an iterate with relative KKT residual `r` (and remembers it).
    pub fn next(&mut self, r: f64) -> f64 {
        let residual = self.max * r.min(1.0);
        let eta = match (self.rule, self.last) {
            (ForcingRule::Residual, _) | (ForcingRule::EisenstatWalker, None) => residual,
            (ForcingRule::EisenstatWalker, Some((r_last, eta_last))) => {
                let mut eta = EW_GAMMA * (r / r_last).powf(EW_ALPHA);
                let floor = EW_GAMMA * eta_last.powf(EW_ALPHA);
                if floor > EW_SAFEGUARD {
                    eta = eta.max(floor);
                }
                eta.min(self.max).max((OVERSOLVE_MARGIN * self.tol / r).min(self.max))
            }
        };
        let slow = self.last.is_some_and(|(r_last, _)| r > self.slow * r_last);
        let eta = match self.last {
            Some(_) if slow && self.slow > 0.0 => eta.max(self.max),
            Some((r_last, _)) if self.last_margin > 0.0 && r * (r / r_last).powi(2) > self.last_margin * self.tol => {
                eta.max((EW_GAMMA * (r / r_last).powf(EW_ALPHA)).min(self.max))
            }
            _ => eta,
        };
        self.last = Some((r, eta));
        eta
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_residual_rule_is_proportional_to_r_below_one() {
        let mut f = ForcingTerms::new(ForcingRule::Residual, 1e-2, 1e-10);
        assert_eq!(f.next(3.0), 1e-2);
        assert_eq!(f.next(0.5), 5e-3);
        assert_eq!(f.next(1e-6), 1e-8);
    }

    #[test]
    fn eisenstat_walker_follows_the_squared_contraction_within_its_safeguards() {
        let mut f = ForcingTerms::new(ForcingRule::EisenstatWalker, 1e-2, 1e-10);
        // the first step has no contraction to go by: the residual rule
        assert_eq!(f.next(0.5), 5e-3);
        // r halves: 0.9 · 0.25 = 0.225, capped at η_max
        assert_eq!(f.next(0.25), 1e-2);
        // r falls by 1e3: 0.9e-6 (the safeguard 0.9 · 1e-4 is below 0.1)
        let eta = f.next(2.5e-4);
        assert!((eta - 0.9e-6).abs() < 1e-18, "{eta}");
        // r falls by 1e5 more: 0.9e-10 would oversolve; a tenth of tol / r = 0.4e-6 is enough
        let eta = f.next(2.5e-9);
        assert!((eta - 0.4e-2).abs() < 1e-15, "{eta}");
        // with η_max = 0.5, after η = 0.5 the safeguard 0.9 · 0.25 = 0.225 > 0.1 bounds the next
        let mut g = ForcingTerms::new(ForcingRule::EisenstatWalker, 0.5, 1e-10);
        assert_eq!(g.next(2.0), 0.5);
        let eta = g.next(0.2); // 0.9 · 0.01 = 0.009 < 0.225
        assert!((eta - 0.225).abs() < 1e-15, "{eta}");
    }

    #[test]
    fn a_slowly_falling_residual_is_solved_to_eta_max_and_a_fast_one_by_the_rule() {
        // the P1 default scene's plastic steps (docs/plastic_tangent.md): r = 0.246, 0.0917
        // (contraction 0.37: slow), 0.0203 (0.22: slow), 5.2e-4 (0.026: fast), 1.8e-6
        let mut f = ForcingTerms::new(ForcingRule::Residual, 1e-2, 1e-10).slow_below(SLOW_CONTRACTION);
        assert_eq!(f.next(0.246), 2.46e-3, "no contraction known yet: the rule");
        assert_eq!(f.next(0.0917), 1e-2);
        assert_eq!(f.next(0.0203), 1e-2);
        assert!((f.next(5.2e-4) - 5.2e-6).abs() < 1e-20);
        assert!((f.next(1.8e-6) - 1.8e-8).abs() < 1e-22);
        // a residual that rises is slow too
        assert_eq!(f.next(1e-5), 1e-2);
    }

    #[test]
    fn a_fast_step_that_is_not_the_last_is_solved_to_eisenstat_walker_and_the_last_by_the_rule() {
        let mut f = ForcingTerms::new(ForcingRule::Residual, 1e-2, 1e-10)
            .slow_below(SLOW_CONTRACTION)
            .relaxed_before_the_last(LAST_STEP_MARGIN);
        f.next(0.0917);
        f.next(0.0203);
        // model 5.2e-4 · (5.2e-4 / 0.0203)² = 3.4e-7 > 100 tol: not the last, 0.9 · 6.6e-4
        let eta = f.next(5.2e-4);
        assert!((eta - 0.9 * (5.2e-4f64 / 0.0203).powi(2)).abs() < 1e-15, "{eta}");
        assert!(eta > 100.0 * 5.2e-6, "{eta} against the rule's 5.2e-6");
        // model 1.8e-6 · (1.8e-6 / 5.2e-4)² = 2.2e-11 < 100 tol: maybe the last, the rule's term
        assert!((f.next(1.8e-6) - 1.8e-8).abs() < 1e-22);
    }
}
