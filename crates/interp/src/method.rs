//! The interpolator trait shared by every method.
pub use crate::crop::BoxReach;
use crate::crop::LabelBox;
use crate::sdf::SdfCache;
use interslice_core::mesh::TriMesh;
use interslice_core::{Axis, Cancel, Mask, Volume};
use thiserror::Error;

/// Errors of interpolation; messages are one line for the user.
#[derive(Debug, Error)]
pub enum InterpError {
    /// Fewer than two drawn slices, or other unusable input.
    #[error("{0}")]
    Input(String),
    /// A core error (geometry, slice range).
    #[error(transparent)]
    Core(#[from] interslice_core::CoreError),
    /// A run on a label's box ([`SparseMask::in_box`]) would read or paint
    /// past the box's sides: the runner runs it again on a larger box or
    /// the whole volume, so a user never sees this.
    #[error("the interpolation reaches past the label's box")]
    OutsideBox,
}

/// A label's interpolated mask and, when asked for, its confidence per voxel.
pub type WithConfidence = (Mask, Option<Volume<f32>>);

/// The input of one interpolation: one label's mask, whose drawn slices
/// along `axis` carry the tracing, and the sorted, de-duplicated drawn indices.
#[derive(Debug, Clone, Copy)]
pub struct SparseMask<'a> {
    /// Foreground voxels of the label on the drawn slices (other slices ignored).
    pub mask: &'a Mask,
    /// Axis the slices were drawn along.
    pub axis: Axis,
    /// Drawn slice indices along `axis`, sorted ascending, no duplicates.
    pub drawn: &'a [usize],
    /// Checked between slices (and between the stages of a method), so a
    /// request that is dropped or timed out stops within one slice's work.
    pub cancel: Option<&'a Cancel>,
    /// Signed distance maps of the drawn slices already computed
    /// ([`SdfCache`]): the runs of `shape-auto` share them.
    pub maps: Option<&'a SdfCache>,
    /// The in-plane sides of `mask` are a box's inside the volume
    /// ([`crate::crop`]), not the volume's: a method that follows objects
    /// past the drawn outlines ([`BoxReach::Drift`]) returns
    /// [`InterpError::OutsideBox`] where it would read or paint past them,
    /// instead of clamping there as it does at the volume's sides.
    pub in_box: bool,
    /// The only skipped slices the caller reads, sorted (a leave-one-out
    /// run reads its held-out slices and nothing between them): a method
    /// may leave every other skipped slice empty. `None`: all of them.
    /// Across four times the gap two of every three skipped slices of the
    /// stack are never read, and filling them was a third of the default's
    /// time on a round nucleus. [`crate::slices::assemble`] honours it; a
    /// method that reads its own result between slices (the image method's
    /// walk reads its prior on every slice) runs with `None` instead. The
    /// property test `a_run_for_some_slices_gives_those_slices_of_the_whole_run`
    /// holds every method of `methods()` to it.
    pub only: Option<&'a [usize]>,
}

impl<'a> SparseMask<'a> {
    /// The input of one label's interpolation (never cancelled).
    pub fn new(mask: &'a Mask, axis: Axis, drawn: &'a [usize]) -> SparseMask<'a> {
        SparseMask {
            mask,
            axis,
            drawn,
            cancel: None,
            maps: None,
            in_box: false,
            only: None,
        }
    }

    /// The same input, stopped with `Err(Cancelled)` once `cancel` is.
    pub fn with_cancel(self, cancel: &'a Cancel) -> SparseMask<'a> {
        SparseMask {
            cancel: Some(cancel),
            ..self
        }
    }

    /// The same input, reading the drawn slices' maps from `maps`.
    pub fn with_maps(self, maps: &'a SdfCache) -> SparseMask<'a> {
        SparseMask {
            maps: Some(maps),
            ..self
        }
    }

    /// The same input, marked as a label's box ([`SparseMask::in_box`]).
    pub fn inside_box(self) -> SparseMask<'a> {
        SparseMask {
            in_box: true,
            ..self
        }
    }

    /// The same input for another mask and drawn list (a stack of its drawn
    /// slices), keeping its cancel, maps and box; every slice of it is read.
    pub fn on<'b>(&self, mask: &'b Mask, drawn: &'b [usize]) -> SparseMask<'b>
    where
        'a: 'b,
    {
        SparseMask {
            mask,
            drawn,
            only: None,
            ..*self
        }
    }

    /// The same input, of whose skipped slices only `slices` (sorted) are
    /// read ([`SparseMask::only`]).
    pub fn only<'b>(&self, slices: &'b [usize]) -> SparseMask<'b>
    where
        'a: 'b,
    {
        SparseMask {
            only: Some(slices),
            ..*self
        }
    }

    /// The same input, every slice of it read ([`SparseMask::only`]
    /// cleared): for a method that reads its own result between slices.
    pub fn every_slice(self) -> SparseMask<'a> {
        SparseMask { only: None, ..self }
    }

    /// Whether skipped slice `s` is read by the caller ([`SparseMask::only`]).
    pub fn wants(&self, s: usize) -> bool {
        self.only.is_none_or(|o| o.binary_search(&s).is_ok())
    }

    /// Whether the work was cancelled (a loop's cheap test).
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_some_and(Cancel::is_cancelled)
    }

    /// `Err(Cancelled)` once cancelled: the `?` between stages.
    pub fn check_cancelled(&self) -> Result<(), InterpError> {
        match self.cancel {
            Some(c) => Ok(c.check()?),
            None => Ok(()),
        }
    }
}

/// A method that fills the slices between drawn slices.
///
/// Every implementation must: reproduce the drawn slices exactly (or document
/// a mesh-based deviation), never put voxels on a drawn slice that is empty,
/// work along any axis with anisotropic spacing (`mask.geometry().spacing`).
pub trait Interpolator: Send + Sync {
    /// The `--method` name, e.g. `shape-based`.
    fn name(&self) -> &'static str;
    /// One line for `interpolate --list`.
    fn description(&self) -> &'static str;
    /// Interpolate one label's mask.
    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError>;
    /// Interpolate and say how sure the result is per voxel, in `[0.5, 1]`
    /// (see [`crate::confidence`]). By default, from the distance to the
    /// result's boundary and to the nearest drawn slice.
    fn interpolate_with_confidence(
        &self,
        input: SparseMask<'_>,
    ) -> Result<(Mask, Volume<f32>), InterpError> {
        let m = self.interpolate(input)?;
        let c = crate::confidence::shape_confidence(&m, &input, 1.0);
        Ok((m, c))
    }
    /// How far past the label's drawn outlines the method reads, so that
    /// the runner can work on the label's box alone ([`crate::crop`]).
    /// Image-aware methods (whose statistics depend on the surroundings)
    /// and mesh methods keep the default, [`BoxReach::Whole`].
    fn box_reach(&self) -> BoxReach {
        BoxReach::Whole
    }
    /// The same method on the part `b` of the volume (a label's box,
    /// [`crate::crop`]): `None` for the methods that read nothing but the
    /// mask, used as they are; the image-aware method cuts its image to the
    /// box.
    fn for_box(&self, b: &LabelBox) -> Option<Box<dyn Interpolator>> {
        let _ = b;
        None
    }
    /// The same method for a compact stack of the slices `real` along `axis`
    /// (leave-one-out predicts a drawn slice from such a stack,
    /// [`crate::loo::stack`]): `None` for the methods that read nothing but
    /// the mask, used as they are; the image-aware method stacks its image
    /// the same way.
    fn for_stack(
        &self,
        axis: Axis,
        real: &[usize],
    ) -> Result<Option<Box<dyn Interpolator>>, InterpError> {
        let _ = (axis, real);
        Ok(None)
    }
    /// The surface a mesh-based method builds from the drawn slices, in
    /// physical (x, y, z), before the drawn slices are restored (see
    /// [`crate::mesh`]); `Ok(None)` for the methods that work on voxels, whose
    /// surface is that of their result ([`crate::mesh::mask_surface`]).
    fn surface_mesh(&self, input: SparseMask<'_>) -> Result<Option<TriMesh>, InterpError> {
        let _ = input;
        Ok(None)
    }
}

impl SparseMask<'_> {
    /// Check what every method relies on: at least two drawn slices, sorted,
    /// unique and inside the volume. Returns the number of slices along the axis.
    pub fn validate(&self) -> Result<usize, InterpError> {
        let n = self.mask.slice_count(self.axis);
        if self.drawn.len() < 2 {
            return Err(InterpError::Input(format!(
                "interpolation needs at least two drawn slices along {}, got {}",
                self.axis,
                self.drawn.len()
            )));
        }
        if let Some(&bad) = self.drawn.iter().find(|&&d| d >= n) {
            return Err(InterpError::Input(format!(
                "drawn slice {}={bad} is out of range (0..{n})",
                self.axis
            )));
        }
        if self.drawn.windows(2).any(|w| w[0] >= w[1]) {
            return Err(InterpError::Input(
                "drawn slice indices must be sorted ascending without duplicates".into(),
            ));
        }
        Ok(n)
    }
}
