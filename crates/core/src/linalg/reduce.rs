//! Parallel sums whose rounding does not depend on the threads: the terms are added leaf by
//! leaf, in order, and the leaves' sums along a binary tree fixed by the index range alone
//! (rayon's `sum` follows its work stealing, so that the same operands could give different
//! last bits from run to run, and an ill-conditioned CG a different iteration count). The same
//! operands give the same bits on any number of threads (docs/solvers.md, "Reproducible
//! sums").

use std::ops::Range;

/// The largest range one task sums in order.
pub const LEAF: usize = 4096;

/// Where a range of more than one leaf is split: after half of its leaves.
fn split(range: &Range<usize>) -> usize {
    range.start + range.len().div_ceil(LEAF) / 2 * LEAF
}

/// Σ over the leaves of `range` of `f(leaf)`, along the fixed tree.
pub fn tree_sum<F: Fn(Range<usize>) -> f64 + Sync>(range: Range<usize>, f: &F) -> f64 {
    if range.len() <= LEAF {
        return f(range);
    }
    let mid = split(&range);
    let (a, b) = rayon::join(|| tree_sum(range.start..mid, f), || tree_sum(mid..range.end, f));
    a + b
}

/// [`tree_sum`] for a sum that also writes two slices: `f(x, y, leaf)` is given the leaf's parts
/// of `x` and `y` (indices `leaf` of the whole).
pub fn tree_sum_mut<F>(x: &mut [f64], y: &mut [f64], f: &F) -> f64
where
    F: Fn(&mut [f64], &mut [f64], Range<usize>) -> f64 + Sync,
{
    assert_eq!(x.len(), y.len());
    fn go<F>(x: &mut [f64], y: &mut [f64], range: Range<usize>, f: &F) -> f64
    where
        F: Fn(&mut [f64], &mut [f64], Range<usize>) -> f64 + Sync,
    {
        if range.len() <= LEAF {
            return f(x, y, range);
        }
        let mid = split(&range);
        let (x0, x1) = x.split_at_mut(mid - range.start);
        let (y0, y1) = y.split_at_mut(mid - range.start);
        let (a, b) = rayon::join(|| go(x0, y0, range.start..mid, f), || go(x1, y1, mid..range.end, f));
        a + b
    }
    go(x, y, 0..x.len(), f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Terms whose sum depends on the order of addition (each huge term cancels only with its
    /// partner), so that a different association would show in the bits.
    fn terms(n: usize) -> Vec<f64> {
        (0..n).map(|i| if i % 2 == 0 { 1e16 + i as f64 } else { -1e16 + 0.1 * i as f64 }).collect()
    }

    #[test]
    fn the_sum_is_the_same_on_one_and_on_four_threads_and_equals_the_exact_one() {
        let v = terms(10 * LEAF + 124); // even: every big term has its partner
        let sum = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| tree_sum(0..v.len(), &|r| v[r].iter().sum()))
        };
        let one = sum(1);
        for _ in 0..5 {
            assert_eq!(sum(4).to_bits(), one.to_bits());
        }
        // the leaves pair 1e16 + i with −1e16 + 0.1(i+1): exact sum 1.1 Σ_even i + 0.1 n_even
        // up to the rounding of 1e16 + i (spacing 2): within a few units per pair
        let exact: f64 = (0..v.len()).step_by(2).map(|i| 1.1 * i as f64 + 0.1).sum();
        assert!((one - exact).abs() <= 2.0 * v.len() as f64, "{one} against {exact}");
    }

    #[test]
    fn the_writing_sum_writes_every_entry_once_and_sums_like_the_reading_one() {
        let n = 3 * LEAF + 7;
        let (mut x, mut y) = (vec![1.0; n], vec![2.0; n]);
        let s = tree_sum_mut(&mut x, &mut y, &|x, y, r| {
            let mut s = 0.0;
            for ((x, y), i) in x.iter_mut().zip(y.iter_mut()).zip(r) {
                *x += i as f64;
                *y *= 3.0;
                s += *x;
            }
            s
        });
        assert!(x.iter().enumerate().all(|(i, &v)| v == 1.0 + i as f64));
        assert!(y.iter().all(|&v| v == 6.0));
        assert_eq!(s, tree_sum(0..n, &|r| r.map(|i| 1.0 + i as f64).sum()));
        assert_eq!(s, (n * (n + 1) / 2) as f64);
    }
}
