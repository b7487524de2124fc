//! `nearest`: every skipped slice is a copy of the nearest drawn slice (the
//! earlier one on a tie). The simplest anchor of the benchmark: it keeps every
//! piece of a many-piece tracing as drawn, so on fields of small objects that
//! appear and vanish between drawn slices it is hard to beat. Nothing is
//! produced outside the drawn range.
use crate::slices::{assemble, bracket, drawn_slices};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// Nearest-slice copy.
#[derive(Debug, Default, Clone, Copy)]
pub struct Nearest;

impl Interpolator for Nearest {
    fn box_reach(&self) -> BoxReach {
        BoxReach::Outline
    }

    fn name(&self) -> &'static str {
        "nearest"
    }

    fn description(&self) -> &'static str {
        "copy of the nearest drawn slice (the earlier one on a tie)"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let slices = drawn_slices(&input);
        let drawn = input.drawn;
        assemble(&input, |s| {
            let g = bracket(drawn, s)?;
            let (a, b) = (drawn[g], drawn[g + 1]);
            let pick = if s - a <= b - s { g } else { g + 1 };
            Some(slices[pick].clone())
        })
    }
}
