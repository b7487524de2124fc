//! Several labels at once: each label is interpolated on its own (labels in
//! parallel) and the results are painted in ascending label order, so an inner
//! structure (higher label) overwrites the one that contains it. Labels traced
//! side by side split a voxel both claim by depth ([`crate::contest`]).
//!
//! A label volume is a painted partition, so the cell's voxels on a drawn
//! slice are the cell *minus* its nucleus. The outline the person traced is
//! recovered before interpolating: holes of a label's mask that are filled
//! entirely by higher labels (the nucleus inside the cell) belong to the
//! label's own mask. Holes holding background stay holes. Painting in
//! ascending order then reproduces every drawn slice exactly.
//!
//! A method that reads no further than its tracing's surroundings
//! ([`Interpolator::box_reach`]) runs on the label's box only
//! ([`crate::crop`]).
use crate::contest;
use crate::crop::{DrawnSlice, LabelBox, drawn_planes, grow_extent};
use crate::method::WithConfidence;
use crate::{InterpError, Interpolator, SparseMask};
use interslice_core::morph::Connectivity;
use interslice_core::regions::whole_structure;
use interslice_core::{Axis, Cancel, Geometry, LabelVolume, Mask, Volume, Voxel};
use rayon::prelude::*;

/// Most labels a caller interpolates unless told otherwise: every label an
/// 8-bit label volume can hold. Each label is interpolated on its own, so an
/// intensity image read as labels would run for minutes; the CLI's
/// `--max-labels` and Python's `max_labels` default to this.
pub const DEFAULT_MAX_LABELS: usize = 255;

/// Interpolate every label of `sparse` from its drawn slices along `axis`.
///
/// `drawn` lists the drawn slice indices (any order, duplicates allowed); a
/// drawn slice without a label is a known-empty slice for that label. Errors
/// for fewer than two drawn slices or an index out of range.
pub fn interpolate_labels(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<LabelVolume, InterpError> {
    interpolate_labels_as(method, sparse, axis, drawn, |l| l)
}

/// [`interpolate_labels`] painting `value(label)` into a volume of another
/// voxel type, so a caller holding labels in a narrower or wider type (a
/// numpy array of uint8, a mask) gets its result without converting the
/// whole volume afterwards.
pub fn interpolate_labels_as<T: Voxel>(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
    value: impl Fn(u16) -> T,
) -> Result<Volume<T>, InterpError> {
    interpolate_drawn_as(method, &DrawnLabels::read_any(sparse, axis, drawn)?, value)
}

/// [`interpolate_labels_as`] from drawn slices already read (a caller that
/// holds them in another form, such as a numpy array, builds them with
/// [`DrawnLabels::of_planes`] and never a whole sparse volume).
pub fn interpolate_drawn_as<T: Voxel>(
    method: &dyn Interpolator,
    planes: &DrawnLabels,
    value: impl Fn(u16) -> T,
) -> Result<Volume<T>, InterpError> {
    Ok(run(method, planes, false, value)?.0)
}

/// [`interpolate_labels`] with the confidence per voxel: the least
/// confidence of any label there (each label's from
/// [`Interpolator::interpolate_with_confidence`]), 1 where no label is unsure.
/// A shape method runs on the label's box grown until its confidence
/// reaches [`crate::crop::SURE`] at the sides
/// ([`LabelBox::grown_for_confidence`]); outside, where the whole volume's
/// confidence lies between that and 1, it is 1.
pub fn interpolate_labels_with_confidence(
    method: &dyn Interpolator,
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<(LabelVolume, Volume<f32>), InterpError> {
    let planes = DrawnLabels::read_any(sparse, axis, drawn)?;
    interpolate_drawn_with_confidence_as(method, &planes, |l| l)
}

/// [`interpolate_labels_with_confidence`] from drawn slices already read,
/// painting `value(label)` ([`interpolate_drawn_as`]).
pub fn interpolate_drawn_with_confidence_as<T: Voxel>(
    method: &dyn Interpolator,
    planes: &DrawnLabels,
    value: impl Fn(u16) -> T,
) -> Result<(Volume<T>, Volume<f32>), InterpError> {
    let (labels, conf) = run(method, planes, true, value)?;
    Ok((labels, conf.expect("confidence requested")))
}

/// A label's result, with its confidence when asked: on its box
/// ([`crate::crop`]) or on the whole volume.
enum Piece {
    Boxed(LabelBox, Mask, Option<Volume<f32>>),
    Whole(Mask, Option<Volume<f32>>),
}

/// A label's result.
type LabelResult = Result<Piece, InterpError>;

fn run<T: Voxel>(
    method: &dyn Interpolator,
    planes: &DrawnLabels,
    confidence: bool,
    value: impl Fn(u16) -> T,
) -> Result<(Volume<T>, Option<Volume<f32>>), InterpError> {
    let (axis, drawn, geometry) = (planes.axis, &planes.drawn, &planes.geometry);
    if drawn.len() < 2 {
        return Err(InterpError::Input(format!(
            "interpolation needs at least two drawn slices along {axis}, got {}",
            drawn.len()
        )));
    }
    let labels = &planes.labels;
    let mut out: Volume<T> = zeros_in_parallel(geometry.clone());
    // Per label, the labels traced inside it, worked out where a contest
    // asks ([`DrawnLabels::held_by`]).
    let mut held: Vec<Option<Vec<u16>>> = vec![None; labels.len()];
    let mut conf: Option<Volume<f32>> =
        confidence.then(|| Volume::filled(geometry.clone(), 1.0f32));
    // With the confidence every label's result is a whole volume of
    // masks and floats (5 bytes a voxel, 640 MiB at 512³): as many labels
    // at a time as there are cores, not all of them at once.
    let batch = if confidence {
        rayon::current_num_threads().max(1)
    } else {
        labels.len().max(1)
    };
    for first in (0..labels.len()).step_by(batch) {
        let last = (first + batch).min(labels.len());
        let results: Vec<LabelResult> = (first..last)
            .into_par_iter()
            .map(|li| {
                let filled = planes.traced(li);
                let slices: Vec<DrawnSlice<'_>> = drawn
                    .iter()
                    .zip(&filled)
                    .enumerate()
                    .map(|(i, (&index, inside))| DrawnSlice {
                        index,
                        inside,
                        extent: planes.extent(i, li),
                    })
                    .collect();
                let whole = |confidence: bool| {
                    let m = planes.on_grid(&filled);
                    whole_run(method, SparseMask::new(&m, axis, drawn), confidence)
                };
                label_piece(
                    method,
                    (geometry, axis, drawn),
                    &slices,
                    confidence,
                    None,
                    whole,
                )
            })
            .collect();
        for (li, r) in (first..last).zip(results) {
            let v = value(labels[li]);
            // A lower label painted as `a` that this one was traced inside.
            let nests = |a: T| {
                labels[..li]
                    .iter()
                    .position(|&k| value(k) == a)
                    .is_some_and(|outer| {
                        held[outer]
                            .get_or_insert_with(|| planes.held_by(outer))
                            .contains(&labels[li])
                    })
            };
            let (b, m, c) = match r? {
                Piece::Boxed(b, m, c) => (b, m, c),
                Piece::Whole(m, c) => (LabelBox::whole(geometry), m, c),
            };
            if li == 0 {
                // Nothing painted yet: nothing to contest.
                b.paint(&mut out, &m, v);
            } else {
                contest::paint(&mut out, &b, &m, v, axis, nests);
            }
            if let (Some(all), Some(c)) = (conf.as_mut(), c) {
                b.lower(all, &c);
            }
        }
    }
    Ok((out, conf))
}

/// One label's result: on the boxes [`LabelBox::tries`] gives for the
/// method, the smallest that holds it, else `whole(confidence)` on the
/// whole volume. With the confidence, a box is grown until the confidence
/// reaches [`crate::crop::SURE`] at its sides, for the methods whose
/// confidence allows it ([`crate::crop::BoxReach::confidence_on_box`]).
fn label_piece(
    method: &dyn Interpolator,
    (geometry, axis, drawn): (&Geometry, Axis, &[usize]),
    slices: &[DrawnSlice<'_>],
    confidence: bool,
    cancel: Option<&Cancel>,
    whole: impl FnOnce(bool) -> Result<WithConfidence, InterpError>,
) -> LabelResult {
    let reach = method.box_reach();
    for b in LabelBox::tries(geometry, axis, slices, reach) {
        // The confidence reaches further than the result: a larger box, or
        // the whole volume.
        let b = if confidence {
            let grown = reach
                .confidence_on_box()
                .then(|| b.grown_for_confidence(geometry, axis, drawn))
                .flatten();
            let Some(grown) = grown else {
                break;
            };
            grown
        } else {
            b
        };
        if let Some((m, c)) = b.interpolate(method, (geometry, axis), slices, confidence, cancel)? {
            return Ok(Piece::Boxed(b, m, c));
        }
    }
    let (m, c) = whole(confidence)?;
    Ok(Piece::Whole(m, c))
}

/// `method` on the whole volume's `input`, with its confidence when asked.
fn whole_run(
    method: &dyn Interpolator,
    input: SparseMask<'_>,
    confidence: bool,
) -> Result<WithConfidence, InterpError> {
    if confidence {
        let (m, c) = method.interpolate_with_confidence(input)?;
        Ok((m, Some(c)))
    } else {
        Ok((method.interpolate(input)?, None))
    }
}

/// One label's mask interpolated as [`interpolate_labels`] interpolates
/// each label: on the label's box where the method allows it
/// ([`crate::crop`]), the result pasted into a mask of the whole volume;
/// with `confidence`, its confidence too (1 outside the box, as
/// [`interpolate_labels_with_confidence`] takes it). For a caller that
/// holds one label's mask, such as the server's preview; `input`'s
/// cancellation token stops the box's run as the whole volume's.
pub fn interpolate_label(
    method: &dyn Interpolator,
    input: SparseMask<'_>,
    confidence: bool,
) -> Result<WithConfidence, InterpError> {
    input.validate()?;
    let (axis, geometry) = (input.axis, input.mask.geometry());
    let planes = drawn_planes(&input)?;
    let slices = DrawnSlice::of(&input, &planes);
    let whole = |confidence: bool| whole_run(method, input, confidence);
    let piece = label_piece(
        method,
        (geometry, axis, input.drawn),
        &slices,
        confidence,
        input.cancel,
        whole,
    )?;
    Ok(match piece {
        Piece::Whole(m, c) => (m, c),
        Piece::Boxed(b, m, c) => b.onto_volume(geometry, (m, c)),
    })
}

/// A volume of zeros written by every core: an output of one volume's size
/// is mostly memory the allocator hands back from an earlier one (a loop
/// over volumes, Python arrays freed and allocated again), which must be
/// cleared, and one core clears it at a fraction of the memory bandwidth.
///
/// The zeros are collected in blocks of [`ZERO_BLOCK`] values, each block
/// one copy that runs at memory speed; collected value by value, the
/// writes were not vectorised and took longer than the painting.
pub(crate) fn zeros_in_parallel<T: Voxel>(geometry: Geometry) -> Volume<T> {
    let n = geometry.len();
    let mut data = rayon::iter::repeat_n([T::default(); ZERO_BLOCK], n.div_ceil(ZERO_BLOCK))
        .collect::<Vec<_>>()
        .into_flattened();
    data.truncate(n);
    Volume::from_vec(geometry, data).expect("one value per voxel")
}

/// Values per block of [`zeros_in_parallel`].
const ZERO_BLOCK: usize = 4096;

/// The drawn slices sorted and de-duplicated; an error names the first one
/// outside the volume along `axis`.
pub fn sorted_drawn(
    sparse: &LabelVolume,
    axis: Axis,
    drawn: &[usize],
) -> Result<Vec<usize>, InterpError> {
    let mut drawn = drawn.to_vec();
    drawn.sort_unstable();
    drawn.dedup();
    let n = sparse.slice_count(axis);
    if let Some(&bad) = drawn.iter().find(|&&d| d >= n) {
        return Err(InterpError::Input(format!(
            "drawn slice {axis}={bad} is out of range (0..{n})"
        )));
    }
    Ok(drawn)
}

/// Labels present on the drawn slices, ascending (each is interpolated on
/// its own, so their number is the cost: callers bound it before
/// interpolating a volume that may be an intensity image). `drawn` must be
/// valid indices along `axis`.
pub fn drawn_labels(sparse: &LabelVolume, axis: Axis, drawn: &[usize]) -> Vec<u16> {
    DrawnLabels::read(sparse, axis, drawn).labels
}

/// The drawn slices of `sparse` along `axis`, row-major.
fn read_planes(sparse: &LabelVolume, axis: Axis, drawn: &[usize]) -> Vec<Vec<u16>> {
    drawn
        .par_iter()
        .map(|&d| sparse.slice(axis, d).expect("validated drawn index"))
        .collect()
}

/// The labels on `plane` (`w` pixels a row), ascending, each with its
/// extent `[u_lo, u_hi, v_lo, v_hi]`. `slot` is a table of `u32::MAX` for
/// every label value, handed back as it came: it maps a label met on this
/// plane to its entry, so a label's runs are found without a search.
fn plane_extents(plane: &[u16], w: usize, slot: &mut [u32]) -> Vec<(u16, [usize; 4])> {
    let mut found: Vec<(u16, Option<[usize; 4]>)> = Vec::new();
    for (v, row) in plane.chunks_exact(w).enumerate() {
        if all_zero(row) {
            continue;
        }
        // Runs of one label: their first and last pixels bound the extent.
        let mut u = 0;
        while u < w {
            let l = row[u];
            let start = u;
            while u < w && row[u] == l {
                u += 1;
            }
            if l == 0 {
                continue;
            }
            let k = match slot[l as usize] {
                u32::MAX => {
                    slot[l as usize] = found.len() as u32;
                    found.push((l, None));
                    found.len() - 1
                }
                k => k as usize,
            };
            grow_extent(&mut found[k].1, start, v);
            grow_extent(&mut found[k].1, u - 1, v);
        }
    }
    for &(l, _) in &found {
        slot[l as usize] = u32::MAX;
    }
    found.sort_unstable_by_key(|&(l, _)| l);
    found
        .into_iter()
        .map(|(l, e)| (l, e.expect("a run was found")))
        .collect()
}

/// Whether every value of `run` is 0 (an OR over the run, which the
/// compiler vectorises, rather than a test per value).
fn all_zero(run: &[u16]) -> bool {
    run.iter().fold(0, |a, &x| a | x) == 0
}

/// The drawn slices of a label volume, read once for all labels: each
/// slice's labels and, per label, its in-plane extent there. A label's
/// traced slices are then worked out on its extent only, so the cost of many
/// labels is their outlines', not the slices' times their number.
pub struct DrawnLabels {
    /// The grid of the label volume, its axis and its drawn slices.
    geometry: Geometry,
    axis: Axis,
    drawn: Vec<usize>,
    /// Slice width and height.
    w: usize,
    h: usize,
    /// Each drawn slice, row-major.
    planes: Vec<Vec<u16>>,
    /// Labels on any drawn slice, ascending.
    labels: Vec<u16>,
    /// Per drawn slice, the labels on it (as indexed in `labels`,
    /// ascending) with their extent `[u_lo, u_hi, v_lo, v_hi]`, as
    /// [`crate::crop`] measures outlines: only the labels present, so the
    /// memory is bounded by the slices' pixels whatever the label count.
    extents: Vec<Vec<(usize, [usize; 4])>>,
}

impl DrawnLabels {
    /// Read the drawn slices of `sparse` along `axis` (valid indices).
    pub fn read(sparse: &LabelVolume, axis: Axis, drawn: &[usize]) -> DrawnLabels {
        let planes = read_planes(sparse, axis, drawn);
        Self::of_planes(sparse.geometry().clone(), axis, drawn, planes)
            .expect("slices read from the volume")
    }

    /// [`DrawnLabels::read`] for drawn indices in any order, duplicates
    /// allowed; an error names the first one outside the volume.
    pub fn read_any(
        sparse: &LabelVolume,
        axis: Axis,
        drawn: &[usize],
    ) -> Result<DrawnLabels, InterpError> {
        Ok(Self::read(
            sparse,
            axis,
            &sorted_drawn(sparse, axis, drawn)?,
        ))
    }

    /// The drawn slices `drawn` (sorted, unique, inside the grid) along
    /// `axis` of a label volume on `geometry`, given as `planes` (row-major,
    /// as [`Volume::slice`] gives them); an error when their number or size
    /// does not fit.
    pub fn of_planes(
        geometry: Geometry,
        axis: Axis,
        drawn: &[usize],
        planes: Vec<Vec<u16>>,
    ) -> Result<DrawnLabels, InterpError> {
        let (a, b) = axis.in_plane();
        let (w, h) = (geometry.dims[a], geometry.dims[b]);
        let n = geometry.dims[axis.dim()];
        if planes.len() != drawn.len()
            || planes.iter().any(|p| p.len() != w * h)
            || drawn.windows(2).any(|p| p[0] >= p[1])
            || drawn.last().is_some_and(|&d| d >= n)
        {
            return Err(InterpError::Input(format!(
                "drawn slices do not fit a {w}x{h} plane with {n} slices along {axis}"
            )));
        }
        // Each plane is read once, in parallel: its labels and their extents.
        let found: Vec<Vec<(u16, [usize; 4])>> = planes
            .par_iter()
            .map_init(
                || vec![u32::MAX; 65536],
                |slot, p| plane_extents(p, w, slot),
            )
            .collect();
        let mut labels: Vec<u16> = found.iter().flatten().map(|&(l, _)| l).collect();
        labels.sort_unstable();
        labels.dedup();
        let extents = found
            .into_iter()
            .map(|f| {
                f.into_iter()
                    .map(|(l, e)| (labels.binary_search(&l).expect("a label found"), e))
                    .collect()
            })
            .collect();
        Ok(DrawnLabels {
            geometry,
            axis,
            drawn: drawn.to_vec(),
            w,
            h,
            planes,
            labels,
            extents,
        })
    }

    /// The drawn slices as a label volume (zero elsewhere).
    pub fn volume(&self) -> LabelVolume {
        self.on_grid(&self.planes)
    }

    /// The labels on any drawn slice, ascending.
    pub fn labels(&self) -> &[u16] {
        &self.labels
    }

    /// The traced mask of `label` on the drawn slices (other slices empty):
    /// the whole structure of the label on each, as a 2D image with
    /// 8-connected holes ([`whole_structure`]); empty when the label is on
    /// no drawn slice.
    pub fn traced_mask(&self, label: u16) -> Mask {
        let filled = match self.labels.binary_search(&label) {
            Ok(li) => self.traced(li),
            Err(_) => vec![vec![false; self.w * self.h]; self.drawn.len()],
        };
        self.on_grid(&filled)
    }

    /// A volume of the label volume's grid holding `slices` on the drawn
    /// slices (one per drawn slice), zero elsewhere.
    fn on_grid<T: Voxel>(&self, slices: &[Vec<T>]) -> Volume<T> {
        let mut m: Volume<T> = Volume::zeros(self.geometry.clone());
        for (&d, f) in self.drawn.iter().zip(slices) {
            m.set_slice(self.axis, d, f).expect("slice shape matches");
        }
        m
    }

    /// The extent of label `li` on drawn slice `i`, `None` when absent.
    fn extent(&self, i: usize, li: usize) -> Option<[usize; 4]> {
        let e = &self.extents[i];
        e.binary_search_by_key(&li, |x| x.0).ok().map(|k| e[k].1)
    }

    /// The labels traced inside label `outer` (an index in
    /// [`DrawnLabels::labels`]): those with a pixel in `outer`'s whole
    /// structure, a hole of it, on some drawn slice; ascending.
    fn held_by(&self, outer: usize) -> Vec<u16> {
        let own = self.labels[outer];
        let mut held: Vec<u16> = self
            .traced(outer)
            .iter()
            .zip(&self.planes)
            .flat_map(|(t, p)| t.iter().zip(p).filter(|&(&t, &l)| t && l != own && l != 0))
            .map(|(_, &l)| l)
            .collect();
        held.sort_unstable();
        held.dedup();
        held
    }

    /// The whole structure of label `li` on each drawn slice
    /// ([`whole_structure`] with 8-connected holes), worked out on its
    /// extent grown by one pixel: a hole is enclosed by the label, so inside
    /// its extent, and the ring of other pixels around the extent is open
    /// as the rest of the slice is.
    fn traced(&self, li: usize) -> Vec<Vec<bool>> {
        let label = self.labels[li];
        let (w, h) = (self.w, self.h);
        self.planes
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let mut out = vec![false; w * h];
                let Some([u0, u1, v0, v1]) = self.extent(i, li) else {
                    return out;
                };
                let (u0, v0) = (u0.saturating_sub(1), v0.saturating_sub(1));
                let (u1, v1) = ((u1 + 1).min(w - 1), (v1 + 1).min(h - 1));
                let cw = u1 - u0 + 1;
                let mut crop: Vec<u16> = Vec::with_capacity(cw * (v1 - v0 + 1));
                for v in v0..=v1 {
                    crop.extend_from_slice(&p[u0 + w * v..=u1 + w * v]);
                }
                let g = Geometry::new([cw, v1 - v0 + 1, 1], [1.0; 3], Default::default())
                    .expect("crop of a valid slice");
                let crop = Volume::from_vec(g, crop).expect("crop size");
                let inside = whole_structure(&crop, label, Connectivity::Full)
                    .into_parts()
                    .1;
                for (v, row) in inside.chunks_exact(cw).enumerate() {
                    let at = u0 + w * (v0 + v);
                    out[at..at + cw].copy_from_slice(row);
                }
                out
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Worked out on each label's extent, the traced slices are the
        /// whole slice's [`whole_structure`], holes, nested labels, thin
        /// labels and labels on the slice's edge included. (Slices one pixel
        /// wide are left out: there [`whole_structure`] sees no side of the
        /// slice, and would fill a slice the label is absent from.)
        #[test]
        fn a_labels_traced_slices_on_its_extent_are_the_whole_slices(
            w in 2usize..12,
            h in 2usize..12,
            seed in proptest::collection::vec(0u16..4, 144 * 2),
        ) {
            let g = Geometry::new([w, h, 2], [1.0; 3], Default::default()).unwrap();
            let data: Vec<u16> = seed[..w * h * 2].to_vec();
            let vol = Volume::from_vec(g, data).unwrap();
            let planes = DrawnLabels::read(&vol, Axis::Z, &[0, 1]);
            for (li, &l) in planes.labels.iter().enumerate() {
                let traced = planes.traced(li);
                for (k, got) in traced.iter().enumerate() {
                    let g1 = Geometry::new([w, h, 1], [1.0; 3], Default::default()).unwrap();
                    let s = Volume::from_vec(g1, vol.slice(Axis::Z, k).unwrap()).unwrap();
                    let want = whole_structure(&s, l, Connectivity::Full).into_parts().1;
                    prop_assert_eq!(got, &want, "label {} slice {}", l, k);
                }
            }
        }
    }
}
