//! The area profile of a structure along the axis, from its drawn slices: the
//! parabola through the areas of a gap's two drawn slices and the drawn slice
//! beyond the end nearer a skipped slice, or, for `shape-area`, the parabolas
//! of both ends blended across the gap ([`profile_area`]). A round structure's area changes
//! along a curve, not a line (`A ∝ R² − z²` towards a pole, `A ∝ z²` along a
//! cone), and three drawn areas are the fewest that see the curve. Used by
//! the advice (how fast the shape bends, `crate::advise`) and by
//! `shape-area` (how much area a skipped slice holds,
//! [`crate::shape_area`]).

/// The three drawn slices (positions in the drawn list) whose areas fit the
/// profile at a skipped slice of gap `g` (between drawn slices `g` and
/// `g + 1`) that is `nearer_start` to drawn slice `g` or not: the gap's two
/// and the one beyond the nearer end, or beyond the other end when that one
/// does not show the structure or does not exist. `None` when the gap's own
/// slices do not both show it (it ends inside the gap) or neither neighbour
/// does. `shows(i)`: drawn slice `i` shows the structure; `n` drawn slices.
pub fn fit_slices(
    g: usize,
    n: usize,
    nearer_start: bool,
    shows: impl Fn(usize) -> bool,
) -> Option<[usize; 3]> {
    if g + 1 >= n || !shows(g) || !shows(g + 1) {
        return None;
    }
    let before = (g >= 1 && shows(g - 1)).then(|| [g - 1, g, g + 1]);
    let after = (g + 2 < n && shows(g + 2)).then(|| [g, g + 1, g + 2]);
    if nearer_start {
        before.or(after)
    } else {
        after.or(before)
    }
}

/// The profile's area at skipped slice `s` of gap `g` (between drawn slices
/// `g` and `g + 1`, at positions `drawn`, with `areas`): where the drawn
/// slices beyond both ends of the gap show the structure, the parabolas
/// through the three drawn areas on either side blended linearly across the
/// gap (`(1 − t) P₋(s) + t P₊(s)`, `t` the fraction of the gap, parabolic
/// blending: Overhauser 1968, Brewer & Anderson 1977), else the one
/// parabola of [`fit_slices`]. `None` where [`fit_slices`] has no fit.
///
/// Why both sides: one parabola through the nearer side's three areas
/// follows every wobble of a hand-traced area there; the blend is a cubic
/// through all four that leans on the nearer side. Measured with
/// `interslice bench` (`shape-area`, k = 1..9): 0.14 up in total, every AAL
/// structure up (0.002–0.019 each), at k = 1 / 3 / 5 / 9 on the AAL family
/// 0.9432 / 0.9137 / 0.8832 / 0.8315 → 0.9447 / 0.9155 / 0.8840 / 0.8318;
/// the T1 classes and brain1 within 0.002 in total.
pub fn profile_area(drawn: &[usize], areas: &[f64], g: usize, s: usize) -> Option<f64> {
    let n = drawn.len();
    let (a, b) = (drawn[g], drawn[g + 1]);
    let fit = fit_slices(g, n, s - a <= b - s, |i| areas[i] > 0.0)?;
    let at = |fit: [usize; 3]| {
        parabola(
            fit.map(|i| drawn[i] as f64),
            fit.map(|i| areas[i]),
            s as f64,
        )
        .0
    };
    let both = g >= 1 && areas[g - 1] > 0.0 && g + 2 < n && areas[g + 2] > 0.0;
    if !both {
        return Some(at(fit));
    }
    let t = (s - a) as f64 / (b - a) as f64;
    Some((1.0 - t) * at([g - 1, g, g + 1]) + t * at([g, g + 1, g + 2]))
}

/// The parabola through `(z[i], y[i])` at `x`: its value, slope and
/// (constant) second derivative.
pub fn parabola(z: [f64; 3], y: [f64; 3], x: f64) -> (f64, f64, f64) {
    // Newton's divided differences.
    let d01 = (y[1] - y[0]) / (z[1] - z[0]);
    let d12 = (y[2] - y[1]) / (z[2] - z[1]);
    let c = (d12 - d01) / (z[2] - z[0]);
    let value = y[0] + d01 * (x - z[0]) + c * (x - z[0]) * (x - z[1]);
    let slope = d01 + c * (2.0 * x - z[0] - z[1]);
    (value, slope, 2.0 * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parabola_through_three_points_is_exact_on_a_quadratic() {
        let f = |x: f64| 3.0 - 2.0 * x + 0.5 * x * x;
        let z = [1.0, 4.0, 6.0];
        let (v, s, c) = parabola(z, z.map(f), 2.5);
        assert!((v - f(2.5)).abs() < 1e-12);
        assert!((s - (-2.0 + 2.5)).abs() < 1e-12);
        assert!((c - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_profile_blends_both_sides_parabolas_and_keeps_a_quadratic() {
        let drawn = [0usize, 4, 8, 12, 16];
        let f = |z: f64| 200.0 + 9.0 * z - 0.6 * z * z;
        let areas = drawn.map(|d| f(d as f64));
        for s in 9..12 {
            let got = profile_area(&drawn, &areas, 2, s).unwrap();
            assert!((got - f(s as f64)).abs() < 1e-9, "{s}");
        }
        // Off a quadratic: the linear blend of the two sides' parabolas,
        // which differ.
        let wobbly = [10.0, 60.0, 50.0, 90.0, 40.0];
        let side = |fit: [usize; 3], s: usize| {
            parabola(
                fit.map(|i| drawn[i] as f64),
                fit.map(|i| wobbly[i]),
                s as f64,
            )
            .0
        };
        let (before, after) = (side([1, 2, 3], 9), side([2, 3, 4], 9));
        assert!((before - after).abs() > 1.0);
        let got = profile_area(&drawn, &wobbly, 2, 9).unwrap();
        assert!((got - (0.75 * before + 0.25 * after)).abs() < 1e-9);
        // One side without the structure beyond it: that side's parabola
        // is not used.
        let ends = [0.0, 60.0, 50.0, 90.0, 40.0];
        let got = profile_area(&drawn, &ends, 1, 5).unwrap();
        let only = parabola([4.0, 8.0, 12.0], [60.0, 50.0, 90.0], 5.0).0;
        assert!((got - only).abs() < 1e-9);
    }

    #[test]
    fn the_fit_takes_the_slice_beyond_the_nearer_end_that_shows_the_structure() {
        let all = |_: usize| true;
        assert_eq!(fit_slices(1, 4, true, all), Some([0, 1, 2]));
        assert_eq!(fit_slices(1, 4, false, all), Some([1, 2, 3]));
        // At the ends only one side exists.
        assert_eq!(fit_slices(0, 4, true, all), Some([0, 1, 2]));
        assert_eq!(fit_slices(2, 4, false, all), Some([1, 2, 3]));
        // A neighbour that does not show it is passed over; a gap whose own
        // slice does not show it, or with no neighbour at all, has no fit.
        assert_eq!(fit_slices(1, 4, true, |i| i != 0), Some([1, 2, 3]));
        assert_eq!(fit_slices(1, 4, true, |i| i != 2), None);
        assert_eq!(fit_slices(0, 2, true, all), None);
    }
}
