//! A cancelled interpolation stops: every method answers `Cancelled` instead
//! of a result, and a run cancelled while it fills the gaps produces no
//! further slice (so a dropped request stops within one slice's work).
use interslice_core::{Axis, Cancel, CoreError, Geometry, LengthUnit, Mask, Volume};
use interslice_interp::slices::assemble;
use interslice_interp::{InterpError, SparseMask, by_name_with_image, methods};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A ball traced on every 6th z slice of a 40³ volume.
fn traced() -> (Mask, Vec<usize>) {
    let g = Geometry::new([40, 40, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let mut m: Mask = Volume::zeros(g);
    let drawn: Vec<usize> = (4..=34).step_by(6).collect();
    for &z in &drawn {
        for y in 0..40 {
            for x in 0..40 {
                let (dx, dy, dz) = (x as f64 - 19.5, y as f64 - 19.5, z as f64 - 19.5);
                if dx * dx + dy * dy + dz * dz <= 15.0 * 15.0 {
                    m.set(x, y, z, true);
                }
            }
        }
    }
    (m, drawn)
}

fn is_cancelled(r: Result<Mask, InterpError>) -> bool {
    matches!(r, Err(InterpError::Core(CoreError::Cancelled)))
}

#[test]
fn every_method_answers_cancelled_once_its_token_is() {
    let (mask, drawn) = traced();
    let cancel = Cancel::new();
    cancel.cancel();
    let image = Arc::new(mask.map(|x| if x { 200.0f32 } else { 20.0 }));
    let mut all = methods();
    all.push(by_name_with_image(None, Some(image.into())).unwrap());
    for m in all {
        let input = SparseMask::new(&mask, Axis::Z, &drawn).with_cancel(&cancel);
        assert!(
            is_cancelled(m.interpolate(input)),
            "{} ran to its end",
            m.name()
        );
        // The same input without the token gives a result.
        assert!(
            m.interpolate(SparseMask::new(&mask, Axis::Z, &drawn))
                .is_ok(),
            "{}",
            m.name()
        );
    }
}

#[test]
fn a_run_cancelled_while_filling_produces_no_further_slice() {
    let (mask, drawn) = traced();
    let cancel = Cancel::new();
    let produced = AtomicUsize::new(0);
    let input = SparseMask::new(&mask, Axis::Z, &drawn).with_cancel(&cancel);
    // One worker thread, so the order is deterministic: the first slice
    // produced cancels the run (as a dropped request would), and no other
    // slice is computed after it.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let r = pool.install(|| {
        assemble(&input, |_| {
            produced.fetch_add(1, Ordering::SeqCst);
            cancel.cancel();
            Some(vec![false; 40 * 40])
        })
    });
    assert!(is_cancelled(r));
    assert_eq!(produced.load(Ordering::SeqCst), 1);
}
