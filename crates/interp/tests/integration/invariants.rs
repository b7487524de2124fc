//! Property tests of the geometry invariants every registered method keeps,
//! on random blobs, random drawn slices, any axis and anisotropic spacing;
//! and the multi-label contract of `interpolate_labels`.
use interslice_core::{Axis, Geometry, LabelVolume, LengthUnit, Mask, Volume};
use interslice_interp::crop::SURE;
use interslice_interp::{
    BoxReach, InterpError, Interpolator, SparseMask, interpolate_labels,
    interpolate_labels_with_confidence, methods,
};
use proptest::prelude::*;

use crate::common::Unboxed;
use std::sync::Mutex;

/// `full` on the `drawn` slices along `axis`, empty elsewhere.
fn drawn_only(full: &Mask, axis: Axis, drawn: &[usize]) -> Mask {
    let mut sparse: Mask = Volume::zeros(full.geometry().clone());
    for &d in drawn {
        sparse
            .set_slice(axis, d, &full.slice(axis, d).unwrap())
            .unwrap();
    }
    sparse
}

/// Up to three random ellipsoids in a small anisotropic volume.
fn blobs() -> impl Strategy<Value = Mask> {
    let ell = (
        0.0f64..1.0,
        0.0f64..1.0,
        0.0f64..1.0,
        2.0f64..7.0,
        2.0f64..7.0,
        2.0f64..9.0,
        -0.6f64..0.6,
    );
    (prop::collection::vec(ell, 1..4), 0.4f64..1.5).prop_map(|(es, sz)| {
        let dims = [18, 16, 20];
        let g = Geometry::new(dims, [1.0, 0.8, sz], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = [i as f64 / 18.0, j as f64 / 16.0, k as f64 / 20.0];
                    let inside = es.iter().any(|e| {
                        // Tilted along z by the shear e.6: objects drift between slices.
                        ((p[0] - e.0 - e.6 * (p[2] - 0.5)) * 18.0 / e.3).powi(2)
                            + ((p[1] - e.1) * 16.0 / e.4).powi(2)
                            + ((p[2] - e.2) * 20.0 / e.5).powi(2)
                            <= 1.0
                    });
                    m.set(i, j, k, inside);
                }
            }
        }
        m
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn drawn_slices_are_kept_and_drawn_empty_slices_stay_empty(
        full in blobs(),
        axis in prop::sample::select(Axis::ALL.to_vec()),
        picks in prop::collection::btree_set(0usize..16, 2..7),
    ) {
        let n = full.slice_count(axis);
        let drawn: Vec<usize> = picks.into_iter().filter(|&d| d < n).collect();
        prop_assume!(drawn.len() >= 2);
        let sparse = drawn_only(&full, axis, &drawn);
        for m in methods() {
            let out = m.interpolate(SparseMask::new(&sparse, axis, &drawn)).unwrap();
            prop_assert_eq!(out.geometry(), full.geometry());
            for &d in &drawn {
                prop_assert_eq!(
                    out.slice(axis, d).unwrap(),
                    full.slice(axis, d).unwrap(),
                    "{} changed drawn slice {}={}", m.name(), axis, d
                );
            }
        }
    }

    /// A caller that reads some skipped slices only (`SparseMask::only`, as
    /// the leave-one-out runs do) gets exactly what the whole run gives on
    /// those slices, and the drawn slices as drawn, from every method.
    #[test]
    fn a_run_for_some_slices_gives_those_slices_of_the_whole_run(
        full in blobs(),
        axis in prop::sample::select(Axis::ALL.to_vec()),
        picks in prop::collection::btree_set(0usize..16, 2..7),
        wanted in prop::collection::btree_set(0usize..16, 1..5),
    ) {
        let n = full.slice_count(axis);
        let drawn: Vec<usize> = picks.into_iter().filter(|&d| d < n).collect();
        prop_assume!(drawn.len() >= 2);
        let wanted: Vec<usize> = wanted.into_iter().filter(|s| *s < n && !drawn.contains(s)).collect();
        let sparse = drawn_only(&full, axis, &drawn);
        for m in methods() {
            let input = SparseMask::new(&sparse, axis, &drawn);
            let whole = m.interpolate(input).unwrap();
            let some = m.interpolate(input.only(&wanted)).unwrap();
            for s in wanted.iter().chain(&drawn) {
                prop_assert_eq!(
                    some.slice(axis, *s).unwrap(),
                    whole.slice(axis, *s).unwrap(),
                    "{} slice {}={}", m.name(), axis, s
                );
            }
        }
    }
}

/// A method as it is, recording the dims of every volume it is run on.
struct Recorded<'a>(&'a dyn Interpolator, Mutex<Vec<[usize; 3]>>);

impl Interpolator for Recorded<'_> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn description(&self) -> &'static str {
        self.0.description()
    }
    fn box_reach(&self) -> BoxReach {
        self.0.box_reach()
    }
    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        self.1.lock().unwrap().push(input.mask.dims());
        self.0.interpolate(input)
    }
    fn interpolate_with_confidence(
        &self,
        input: SparseMask<'_>,
    ) -> Result<(Mask, Volume<f32>), InterpError> {
        self.1.lock().unwrap().push(input.mask.dims());
        self.0.interpolate_with_confidence(input)
    }
}

/// Small random ellipsoids in a wide volume (96 x 88 pixels, 24 slices
/// along z, anisotropic): a label's box, grown for its confidence, is
/// smaller than the volume.
fn small_blobs() -> impl Strategy<Value = Mask> {
    let ell = (
        30.0f64..66.0,
        30.0f64..58.0,
        4.0f64..20.0,
        2.0f64..6.0,
        2.0f64..6.0,
        2.0f64..8.0,
    );
    (prop::collection::vec(ell, 1..3), 0.5f64..1.5).prop_map(|(es, sz)| {
        let dims = [96, 88, 24];
        let g = Geometry::new(dims, [1.0, 0.9, sz], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let inside = es.iter().any(|e| {
                        ((i as f64 - e.0) / e.3).powi(2)
                            + ((j as f64 - e.1) / e.4).powi(2)
                            + ((k as f64 - e.2) / e.5).powi(2)
                            <= 1.0
                    });
                    m.set(i, j, k, inside);
                }
            }
        }
        m
    })
}

/// The `drawn` slices of `full` along `axis` as a sparse label volume
/// (label 3).
fn traced(full: &Mask, axis: Axis, drawn: &[usize]) -> LabelVolume {
    let mut sparse: LabelVolume = Volume::zeros(full.geometry().clone());
    for &d in drawn {
        let s: Vec<u16> = full
            .slice(axis, d)
            .unwrap()
            .iter()
            .map(|&b| u16::from(b) * 3)
            .collect();
        sparse.set_slice(axis, d, &s).unwrap();
    }
    sparse
}

/// Every `step`-th slice of `full` along z from `first`, traced, with the
/// drawn slices.
fn traced_along_z(full: &Mask, first: usize, step: usize) -> (LabelVolume, Vec<usize>) {
    let drawn: Vec<usize> = (first..full.slice_count(Axis::Z)).step_by(step).collect();
    (traced(full, Axis::Z, &drawn), drawn)
}

/// Labels and confidence of `m` on its box and on the whole volume: the
/// same labels, and the same confidence but where the whole volume's is at
/// least [`SURE`] (the box takes it as 1 outside).
fn box_matches_whole_with_confidence(
    m: &dyn Interpolator,
    sparse: &LabelVolume,
    drawn: &[usize],
) -> Result<Vec<[usize; 3]>, TestCaseError> {
    let recorded = Recorded(m, Mutex::new(Vec::new()));
    let (boxed, c_boxed) =
        interpolate_labels_with_confidence(&recorded, sparse, Axis::Z, drawn).unwrap();
    let (whole, c_whole) = interpolate_labels_with_confidence(
        &Unboxed(interslice_interp::by_name(m.name()).unwrap()),
        sparse,
        Axis::Z,
        drawn,
    )
    .unwrap();
    prop_assert!(boxed == whole, "{} labels differ on its box", m.name());
    for (&b, &w) in c_boxed.data().iter().zip(c_whole.data()) {
        prop_assert!(
            b == w || (b == 1.0 && w >= SURE),
            "{}: confidence {} on the box, {} on the whole volume",
            m.name(),
            b,
            w
        );
    }
    Ok(recorded.1.into_inner().unwrap())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// The label runner may run a method on the label's box only
    /// (`interslice_interp::crop`, every method but the image-aware, mesh
    /// and `linear` ones, the default included): the result must be the
    /// whole volume's, voxel for voxel, whatever the blobs, the axis and the
    /// drawn slices (5000 cases checked once).
    #[test]
    fn a_label_box_gives_the_whole_volume_result(
        full in blobs(),
        axis in prop::sample::select(Axis::ALL.to_vec()),
        picks in prop::collection::btree_set(0usize..16, 2..9),
    ) {
        let n = full.slice_count(axis);
        let drawn: Vec<usize> = picks.into_iter().filter(|&d| d < n).collect();
        prop_assume!(drawn.len() >= 2);
        let sparse = traced(&full, axis, &drawn);
        for m in methods().into_iter().filter(|m| m.box_reach() != BoxReach::Whole) {
            let boxed = interpolate_labels(m.as_ref(), &sparse, axis, &drawn).unwrap();
            let name = m.name();
            let whole = interpolate_labels(&Unboxed(m), &sparse, axis, &drawn).unwrap();
            prop_assert!(boxed == whole, "{} differs on its box along {}", name, axis);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// With the confidence, the label runner runs a shape method on the
    /// label's box grown until the confidence reaches `SURE` at its sides
    /// (`LabelBox::grown_for_confidence`): the labels must be the whole
    /// volume's voxel for voxel, the confidence too but where the whole
    /// volume's is at least `SURE` and the box's is 1.
    #[test]
    fn a_label_box_gives_the_whole_volume_confidence(
        full in small_blobs(),
        first in 0usize..3,
        step in 2usize..5,
    ) {
        let (sparse, drawn) = traced_along_z(&full, first, step);
        prop_assume!(drawn.len() >= 2);
        for m in methods().into_iter().filter(|m| m.box_reach() != BoxReach::Whole) {
            box_matches_whole_with_confidence(m.as_ref(), &sparse, &drawn)?;
        }
    }
}

/// The grown box is used where it is smaller than the volume: a ball of
/// radius 5 traced every 3rd slice runs the default on a box, and gives the
/// whole volume's labels and confidence.
#[test]
fn a_small_label_with_its_confidence_runs_on_its_box() {
    let g = Geometry::new([96, 88, 24], [1.0, 1.0, 1.0], LengthUnit::Micrometre).unwrap();
    let mut full: Mask = Volume::zeros(g);
    for k in 0..24 {
        for j in 0..88 {
            for i in 0..96 {
                let r2 = (i as f64 - 48.0).powi(2)
                    + (j as f64 - 44.0).powi(2)
                    + (k as f64 - 12.0).powi(2);
                full.set(i, j, k, r2 <= 25.0);
            }
        }
    }
    let (sparse, drawn) = traced_along_z(&full, 1, 3);
    let m = interslice_interp::by_name(interslice_interp::DEFAULT_METHOD).unwrap();
    let runs = box_matches_whole_with_confidence(m.as_ref(), &sparse, &drawn).unwrap();
    assert_eq!(runs.len(), 1, "{runs:?}");
    // In-plane: the ball (11 pixels), a margin and the confidence's reach.
    assert!(runs[0][0] < 96 && runs[0][1] < 88, "{runs:?}");
}

#[test]
fn labels_are_interpolated_each_on_its_own_and_painted_in_order() {
    // A cell (1) holding a nucleus (2) holding a nucleolus (3); the cell's
    // drawn voxels have the nucleus cut out, as in a painted label volume.
    let g = Geometry::new([30, 30, 30], [1.0, 1.0, 1.0], LengthUnit::Micrometre).unwrap();
    let mut full: LabelVolume = Volume::zeros(g);
    for k in 0..30 {
        for j in 0..30 {
            for i in 0..30 {
                let r = |c: [f64; 3], rad: f64| {
                    ((i as f64 - c[0]).powi(2)
                        + (j as f64 - c[1]).powi(2)
                        + (k as f64 - c[2]).powi(2))
                    .sqrt()
                        <= rad
                };
                let l = if r([15.0, 15.0, 15.0], 3.5) {
                    3
                } else if r([15.0, 15.0, 15.0], 7.0) {
                    2
                } else if r([15.0, 15.0, 15.0], 13.0) {
                    1
                } else {
                    0
                };
                full.set(i, j, k, l);
            }
        }
    }
    let drawn: Vec<usize> = (1..30).step_by(4).collect();
    let mut sparse: LabelVolume = Volume::zeros(full.geometry().clone());
    for &d in &drawn {
        sparse
            .set_slice(Axis::Z, d, &full.slice(Axis::Z, d).unwrap())
            .unwrap();
    }
    for m in methods() {
        let out = interpolate_labels(m.as_ref(), &sparse, Axis::Z, &drawn).unwrap();
        for &d in &drawn {
            assert_eq!(
                out.slice(Axis::Z, d).unwrap(),
                full.slice(Axis::Z, d).unwrap(),
                "{}",
                m.name()
            );
        }
        for l in 1..=3u16 {
            let (mut tp, mut n) = (0usize, 0usize);
            for (&a, &b) in out.data().iter().zip(full.data()) {
                tp += (a == l && b == l) as usize;
                n += (a == l) as usize + (b == l) as usize;
            }
            let dice = 2.0 * tp as f64 / n as f64;
            // The cell must not be hollowed out where the nucleus is: label 1
            // around label 2 on the skipped slice in the middle is a ring.
            // Two originals fall below 0.6 by their documented behaviour:
            // the Gaussian splat inflates every object by at least half the
            // gap (`mesh/splat.rs`), taking most of the thin shell of label 2
            // and doubling the small label 3 (0.373, 0.394 measured), and
            // Delaunay's alpha filter leaves holes in the wide cell shell
            // (`mesh/delaunay.rs`; 0.564 measured); Hoppe's tangent planes
            // are undetermined on an object hardly wider than the gap
            // (`mesh/hoppe.rs`; label 3, 0.568 measured).
            let floor = match (m.name(), l) {
                ("gaussian-splat", 2 | 3) => 0.35,
                ("delaunay", 1) | ("unorganized-points", 3) => 0.5,
                _ => 0.6,
            };
            assert!(dice > floor, "{} label {l}: Dice {dice:.3}", m.name());
        }
        // The centre of a skipped slice inside the nucleolus carries label 3.
        assert_eq!(out.get(15, 15, 15), 3, "{}", m.name());
        // A point of the cell shell on that slice (Delaunay may leave a hole there).
        if m.name() != "delaunay" {
            assert_eq!(out.get(15, 15 - 10, 15), 1, "{}", m.name());
        }
    }
}
