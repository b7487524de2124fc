//! Confidence per voxel of the shape default: fitted on the tracer's own
//! drawn slices, never blunter than the default scale.
use interslice_core::{Axis, Mask, Volume};
use interslice_interp::auto::ShapeAuto;
use interslice_interp::confidence::shape_confidence;
use interslice_interp::protocol::{drawn_for_skip, sparse_of};
use interslice_interp::{Interpolator, SparseMask};

use crate::common::{in_ellipsoid, shape};

/// Mean log-loss of `confidence` as the probability that `result` is right,
/// over the skipped slices between the first and last drawn one.
fn log_loss(truth: &Mask, result: &Mask, confidence: &Volume<f32>, drawn: &[usize]) -> f64 {
    let (mut loss, mut n) = (0.0f64, 0usize);
    for s in drawn[0]..*drawn.last().unwrap() {
        if drawn.contains(&s) {
            continue;
        }
        let (t, r, c) = (
            truth.slice(Axis::Z, s).unwrap(),
            result.slice(Axis::Z, s).unwrap(),
            confidence.slice(Axis::Z, s).unwrap(),
        );
        for ((t, r), c) in t.iter().zip(&r).zip(&c) {
            let p = f64::from(*c).clamp(1e-6, 1.0 - 1e-6);
            loss -= if t == r { p.ln() } else { (1.0 - p).ln() };
            n += 1;
        }
    }
    loss / n as f64
}

/// A smooth ellipsoid traced every sixth slice: the shape is nearly exact,
/// the held-out drawn slices say so, and the fitted confidence scores a
/// lower log-loss on the skipped slices than the default scale, which
/// calls the pixels near the outline far less sure than they are (0.043
/// against 0.097); the result is `interpolate`'s.
#[test]
fn the_shape_defaults_confidence_is_fitted_on_the_drawn_slices() {
    let truth = shape([44, 40, 60], [1.0, 1.0, 1.0], |p| {
        in_ellipsoid(p, [22.0, 20.0, 30.0], [14.0, 11.0, 24.0])
    });
    let drawn = drawn_for_skip(&truth, Axis::Z, 5).unwrap();
    let sparse = sparse_of(&truth, Axis::Z, &drawn);
    let input = SparseMask::new(&sparse, Axis::Z, &drawn);
    let (result, fitted) = ShapeAuto::default()
        .interpolate_with_confidence(input)
        .unwrap();
    assert_eq!(result, ShapeAuto::default().interpolate(input).unwrap());
    let default = shape_confidence(&result, &input, 1.0);
    let (a, b) = (
        log_loss(&truth, &result, &fitted, &drawn),
        log_loss(&truth, &result, &default, &drawn),
    );
    eprintln!("log-loss fitted {a:.5}, default {b:.5}");
    assert!(a < 0.8 * b, "fitted {a:.5} against default {b:.5}");
    // Never blunter than the default (see `auto::held_out_scale`).
    assert!(
        fitted
            .data()
            .iter()
            .zip(default.data())
            .all(|(f, d)| *f >= *d - 1e-6)
    );
}
