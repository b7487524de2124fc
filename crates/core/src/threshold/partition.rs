//! The exact optimal partition of weighted sorted values into `k`
//! contiguous classes, maximising `Σ S_c² / W_c` (equivalently minimising the
//! within-class sum of squares). Multi-class Otsu (on histogram bins) and
//! 1-D k-means (on distinct values) are both this problem.
//!
//! Dynamic programming over the values: `f_m(b) = max_a f_{m-1}(a) + S(a,b)²/W(a,b)`.
//! Up to [`FULL_SEARCH_LIMIT`] values every split is tried (the result equals
//! an exhaustive search, first split on ties); above it the optimal split is
//! monotone in `b` (the within-class cost is Monge), so a divide-and-conquer
//! search finds it in `O(k n log n)`. The sums are accumulated in the same
//! order as the reference searches so that ties resolve identically.

/// Values up to which every split is tried.
pub const FULL_SEARCH_LIMIT: usize = 4096;

/// Prefix sums of the weights and weighted values.
pub struct Prefix {
    w: Vec<f64>,
    s: Vec<f64>,
}

impl Prefix {
    /// Prefix sums of `weights` and `weights * values`, sequential (like `numpy.cumsum`).
    pub fn new(values: &[f64], weights: &[f64]) -> Prefix {
        let mut w = Vec::with_capacity(values.len() + 1);
        let mut s = Vec::with_capacity(values.len() + 1);
        w.push(0.0);
        s.push(0.0);
        let (mut aw, mut asum) = (0.0f64, 0.0f64);
        for (&x, &c) in values.iter().zip(weights) {
            aw += c;
            asum += c * x;
            w.push(aw);
            s.push(asum);
        }
        Prefix { w, s }
    }

    /// `S²/W` of the class holding values `a..b` (`a < b`, `W > 0`).
    #[inline]
    pub fn term(&self, a: usize, b: usize) -> f64 {
        let w = self.w[b] - self.w[a];
        let s = self.s[b] - self.s[a];
        if w > 0.0 { s * s / w } else { 0.0 }
    }

    /// Weight and weighted sum of values `a..b`.
    pub fn class(&self, a: usize, b: usize) -> (f64, f64) {
        (self.w[b] - self.w[a], self.s[b] - self.s[a])
    }
}

/// Optimal class boundaries: the exclusive end index of each of the `k`
/// classes (the last one is `values.len()`). Needs `values.len() >= k >= 1`
/// and positive weights.
pub fn optimal_partition(p: &Prefix, n: usize, k: usize) -> Vec<usize> {
    assert!(k >= 1 && n >= k, "need at least k values");
    // f[b] for the current level, arg[m][b] = start of the last class.
    let mut f: Vec<f64> = (0..=n)
        .map(|b| {
            if b == 0 {
                f64::NEG_INFINITY
            } else {
                p.term(0, b)
            }
        })
        .collect();
    let mut args: Vec<Vec<usize>> = Vec::with_capacity(k);
    args.push(vec![0; n + 1]);
    for m in 2..=k {
        let mut g = vec![f64::NEG_INFINITY; n + 1];
        let mut arg = vec![0usize; n + 1];
        if m == k {
            // Only the full range is needed at the last level.
            let (v, a) = best_split(&f, p, n, m - 1, n - 1);
            g[n] = v;
            arg[n] = a;
        } else if n <= FULL_SEARCH_LIMIT {
            for b in m..=n {
                let (v, a) = best_split(&f, p, b, m - 1, b - 1);
                g[b] = v;
                arg[b] = a;
            }
        } else {
            // Divide and conquer over b with monotone optimal splits.
            let mut stack = vec![(m, n, m - 1, n - 1)];
            while let Some((lo, hi, olo, ohi)) = stack.pop() {
                if lo > hi {
                    continue;
                }
                let mid = (lo + hi) / 2;
                let (v, a) = best_split(&f, p, mid, olo, ohi.min(mid - 1));
                g[mid] = v;
                arg[mid] = a;
                if mid > lo {
                    stack.push((lo, mid - 1, olo, a));
                }
                stack.push((mid + 1, hi, a, ohi));
            }
        }
        args.push(arg);
        f = g;
    }
    let mut ends = vec![0usize; k];
    let mut b = n;
    for m in (0..k).rev() {
        ends[m] = b;
        b = args[m][b];
    }
    ends
}

/// The first `a` in `lo..=hi` maximising `f[a] + term(a, b)`.
#[inline]
fn best_split(f: &[f64], p: &Prefix, b: usize, lo: usize, hi: usize) -> (f64, usize) {
    let mut best = (f64::NEG_INFINITY, lo);
    for (a, &fa) in f.iter().enumerate().take(hi + 1).skip(lo) {
        let v = fa + p.term(a, b);
        if v > best.0 {
            best = (v, a);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(values: &[f64], weights: &[f64], k: usize) -> f64 {
        // All increasing boundary tuples, recursively.
        fn rec(p: &Prefix, start: usize, n: usize, k: usize) -> f64 {
            if k == 1 {
                return p.term(start, n);
            }
            (start + 1..=n - (k - 1))
                .map(|e| p.term(start, e) + rec(p, e, n, k - 1))
                .fold(f64::NEG_INFINITY, f64::max)
        }
        rec(&Prefix::new(values, weights), 0, values.len(), k)
    }

    #[test]
    fn dp_matches_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..50 {
            let n = rng.gen_range(3..12);
            let mut values: Vec<f64> = (0..n).map(|_| rng.gen_range(0.0..100.0)).collect();
            values.sort_by(f64::total_cmp);
            let weights: Vec<f64> = (0..n).map(|_| rng.gen_range(1..20) as f64).collect();
            for k in 1..=3.min(n) {
                let p = Prefix::new(&values, &weights);
                let ends = optimal_partition(&p, n, k);
                let mut start = 0;
                let mut got = 0.0;
                for &e in &ends {
                    got += p.term(start, e);
                    start = e;
                }
                let want = brute(&values, &weights, k);
                assert!(
                    (got - want).abs() <= 1e-9 * want.abs(),
                    "k={k} got {got} want {want}"
                );
            }
        }
    }
}
