//! Finite intensities for the image-aware methods.
//!
//! A float volume may hold NaN or ±∞ (outside a scanner's field of view,
//! a masked-out parameter map, a failed reconstruction). The fusion's edge
//! weights and the walk's standardisation and edge weights are sums over
//! the image, and one non-finite voxel turns them all to NaN: on a ball
//! traced every sixth slice, a few NaN patches beside it took the
//! image-guided result from 0.9999 to 0.937 Dice (the shape alone 0.983).
use interslice_core::Volume;
use rayon::prelude::*;
use std::sync::Arc;

/// `image` with every non-finite voxel given the value of the nearest
/// finite voxel along its row (x; the left one on a tie), or on a row
/// without one the median of the finite voxels (0 where there are none).
/// The same `Arc` where every voxel is finite.
///
/// Why the neighbour's value: it adds no edge where the finite data ends,
/// so neither the fusion's smoothing nor the walk stops at the border of
/// a hole in the data, and the intensity model reads it as it reads the
/// pixels beside it.
pub fn finite(image: Arc<Volume<f32>>) -> Arc<Volume<f32>> {
    if image.data().par_iter().all(|v| v.is_finite()) {
        return image;
    }
    let mut out = (*image).clone();
    let fallback = median_finite(out.data());
    let nx = out.dims()[0];
    out.data_mut()
        .par_chunks_mut(nx)
        .for_each(|row| fill_row(row, fallback));
    Arc::new(out)
}

/// Fill the non-finite values of `row` from their nearest finite one, or
/// with `fallback` where the row has none.
fn fill_row(row: &mut [f32], fallback: f32) {
    if row.iter().all(|v| v.is_finite()) {
        return;
    }
    let finite: Vec<usize> = (0..row.len()).filter(|&i| row[i].is_finite()).collect();
    if finite.is_empty() {
        row.fill(fallback);
        return;
    }
    let mut next = 0; // index into `finite` of the first at or after i
    for i in 0..row.len() {
        while next < finite.len() && finite[next] < i {
            next += 1;
        }
        if row[i].is_finite() {
            continue;
        }
        let before = next.checked_sub(1).map(|k| finite[k]);
        let after = finite.get(next).copied();
        let from = match (before, after) {
            (Some(b), Some(a)) if a - i < i - b => a,
            (Some(b), _) => b,
            (None, Some(a)) => a,
            (None, None) => unreachable!("the row has a finite value"),
        };
        row[i] = row[from];
    }
}

/// The median of the finite values of `data` (0 where there are none).
fn median_finite(data: &[f32]) -> f32 {
    let mut v: Vec<f32> = data.par_iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f32::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, LengthUnit};

    fn volume(dims: [usize; 3], data: Vec<f32>) -> Arc<Volume<f32>> {
        let g = Geometry::new(dims, [1.0; 3], LengthUnit::Millimetre).unwrap();
        Arc::new(Volume::from_vec(g, data).unwrap())
    }

    #[test]
    fn non_finite_voxels_take_the_nearest_finite_value_along_their_row() {
        let (nan, inf) = (f32::NAN, f32::INFINITY);
        let v = volume(
            [5, 3, 1],
            vec![
                nan, 1.0, nan, nan, 4.0, // between two: the nearer, the left on a tie
                2.0, inf, -inf, 9.0, nan, // ±∞ too, and the row's end
                nan, nan, nan, nan, nan, // no finite value: the median of all
            ],
        );
        let f = finite(v);
        assert_eq!(
            f.data(),
            &[
                1.0, 1.0, 1.0, 4.0, 4.0, //
                2.0, 2.0, 9.0, 9.0, 9.0, //
                4.0, 4.0, 4.0, 4.0, 4.0,
            ]
        );
        // Nothing finite at all: zeros.
        let f = finite(volume([2, 1, 1], vec![nan, -inf]));
        assert_eq!(f.data(), &[0.0, 0.0]);
    }

    #[test]
    fn a_finite_image_is_kept_as_it_is() {
        let v = volume([2, 2, 1], vec![1.0, 2.0, 3.0, 4.0]);
        assert!(Arc::ptr_eq(&finite(v.clone()), &v));
    }
}
