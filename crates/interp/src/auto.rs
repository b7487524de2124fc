//! `shape-auto`: the shape-only default. Per label, the shape method that best
//! predicts the tracer's own drawn slices from their neighbours (leave-one-out,
//! [`crate::loo`]) interpolates the volume.
//!
//! The candidates answer different kinds of tracing: `shape-aligned` (matched,
//! aligned objects with caps: single or few objects that drift or tilt),
//! `shape-area` (the blend cut to the area the drawn slices' area profile
//! says: round structures, and pieces that move apart between drawn slices),
//! `shape-based` (plain signed-distance blending: ribbons and porous shapes
//! whose pieces do not correspond one to one) and `nearest` (copies: fields of
//! many small objects that appear and vanish between drawn slices). The
//! choice is the highest pooled Dice over the held-out slices; a candidate
//! must beat the one listed before it by more than [`MARGIN`] to be chosen,
//! so that noise in a few held-out slices does not move off `shape-aligned`.
//! On a field of many pieces drawn far apart `shape-aligned` is not a
//! candidate at all ([`pieces_apart`]): there the held-out slices, twice the
//! gap away, rank it first where it loses.
//! When candidates come within [`CLOSE`] of each other, their errors are
//! also measured across four times the gap and carried back towards the
//! tracer's own gap (`ShapeAuto::extrapolated`), as the best method can
//! change with the gap.
//!
//! **End rule.** No candidate reaches past the first or last drawn slice: the
//! outermost drawn slices are taken as where the tracer saw the object begin
//! and end (the protocol of the benchmark, and what a tracer is asked to do).
//! A structure cut by the tracer's range is continued only by drawing further
//! slices. `shape-aligned` keeps its caps *between* drawn slices (an object
//! that ends inside a gap), where the tracing says the object stops.
use crate::aligned::ShapeAligned;
use crate::confidence::{best_scale, shape_confidence};
use crate::crop::AXIS_SLICES;
use crate::image::fuse::tau;
use crate::jump::{APART, Fade, drifting_gaps, fade, jumping_gaps, overlap_counts};
use crate::loo::{Compact, HeldOut};
use crate::nearest::Nearest;
use crate::sdf::{SdfCache, signed_distance};
use crate::shape_area::{ShapeArea, pole_profile_applies};
use crate::shape_based::ShapeBased;
use crate::slices::{Plane, median_gap, showing};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::morph::Connectivity;
use interslice_core::regions::label_2d;
use interslice_core::{Axis, Mask, Volume};
use rayon::prelude::*;

/// Pooled Dice a later candidate must gain over an earlier one to be chosen.
pub const MARGIN: f64 = 0.002;

/// Leave-one-out choice among the shape methods.
#[derive(Debug, Clone, Copy, Default)]
pub struct ShapeAuto {
    /// Whether this runs on a compact stack of drawn slices
    /// ([`Interpolator::for_stack`]: the leave-one-out of the predicted Dice
    /// and of the advice). There it leaves the gaps across which outlines
    /// jump ([`jumping_gaps`]) to the candidate: held out across twice the
    /// tracer's gap, more outlines jump than on the tracer's own gaps, and
    /// copying the nearer slice there (the jump rule before the fade) made
    /// the predicted Dice of the phantom's cell traced every tenth slice
    /// 0.93 against a true 0.79 (0.87 without).
    on_stack: bool,
}

/// The candidates, in order of preference.
pub fn candidates() -> Vec<Box<dyn Interpolator>> {
    vec![
        Box::new(ShapeAligned { end_caps: false }),
        Box::new(ShapeArea::default()),
        Box::new(ShapeBased),
        Box::new(Nearest),
    ]
}

/// The outcome of the leave-one-out choice.
pub struct Choice {
    /// Index into [`candidates`].
    pub index: usize,
    /// Pooled held-out Dice of every candidate over the held-out slices
    /// between two that show the structure (`interior`); empty where the
    /// choice was made without them.
    pub scores: Vec<f64>,
    /// The chosen candidate's predictions of the held-out slices beside one
    /// that shows the structure (empty where nothing was held out).
    pub held: Vec<HeldOut>,
    /// The compact stack they were predicted on.
    pub compact: Compact,
    /// Whether `shape-area` was taken by rule on too few held-out slices
    /// between two that show the structure ([`FEW_HELD_OUT`]): `held` then
    /// holds predictions across the structure's ends, which do not judge an
    /// image fit either (the image method keeps the shape).
    pub thin: bool,
    /// Where `shape-area` was taken by rule on too few held-out slices of a
    /// structure that spans the traced range ([`FEW_HELD_OUT`]): the
    /// candidate the leave-one-out ranked first, with its predictions,
    /// which the image method reads the image with ([`Choice::ranked_first`]).
    pub ranked: Option<(usize, Vec<HeldOut>)>,
    /// Whether fewer than [`FEW_HELD_OUT`] held-out slices lie between two
    /// that show the structure (and its outline does not drift steadily):
    /// `shape-area` fills it by rule.
    pub few: bool,
}

impl Choice {
    /// The index `shape-auto` fills with, and the choice with the
    /// leave-one-out's own pick in its place where `shape-area` was taken
    /// by rule ([`Choice::ranked`]): the image method's prior. Why: its fit
    /// and walks read the image around that pick's predictions of the
    /// held-out slices, and with the rule's prior instead they lost where
    /// the image shows the edge (lung2 at k = 5–8 −0.019 to −0.13, brain1
    /// at k = 2 −0.22 on the skipped slices of `interslice bench`).
    pub fn ranked_first(mut self) -> (usize, Choice) {
        let shape = self.index;
        if let Some((index, held)) = self.ranked.take() {
            self.index = index;
            self.held = held;
        }
        (shape, self)
    }
}

impl ShapeAuto {
    /// How its result fills the gaps across which the outline jumps: eased
    /// fades, none on a leave-one-out stack (where across twice the gap
    /// more outlines jump than on the tracer's own gaps).
    fn fade(&self) -> Option<Fade> {
        (!self.on_stack).then_some(Fade::Eased)
    }

    /// Choose the candidate for `input` on its drawn slices.
    ///
    /// Only the drawn slices from [`AXIS_SLICES`] before the first that
    /// shows the label to as many after the last are held out in turn:
    /// slices farther out are empty in every prediction and add nothing to
    /// the pooled Dice, and leaving them out makes the choice the same on
    /// the label's box ([`crate::crop`]) as on the whole volume. Only a
    /// drawn slice whose two neighbours both show the structure is scored
    /// (`interior`): one beside an empty slice is predicted across the
    /// object's end, and one between empty slices is predicted empty by
    /// every candidate (on stardist's nuclei as a label volume at k = 9,
    /// where most nuclei show on one drawn slice, those zeros had drowned
    /// the slices next to them: 0.6310 → 0.6518). With fewer than
    /// [`FEW_HELD_OUT`] such slices (but one or more, or an object that
    /// ends inside the traced range, `ends_inside`) `shape-area` is taken.
    pub fn choose(&self, input: &SparseMask<'_>) -> Result<Choice, InterpError> {
        self.choose_on(input, Compact::held_out)
    }

    /// The index of the candidate [`ShapeAuto::choose`] would choose,
    /// ranked on half the held-out slices when there are many
    /// ([`Compact::held_out_to_rank`]): what interpolating needs, where the
    /// predictions themselves are not kept.
    pub fn rank(&self, input: &SparseMask<'_>) -> Result<usize, InterpError> {
        Ok(self.choose_on(input, Compact::held_out_to_rank)?.index)
    }

    /// [`ShapeAuto::choose`] with `held_out` predicting the held-out slices.
    fn choose_on(
        &self,
        input: &SparseMask<'_>,
        held_out: impl Fn(
            &Compact,
            &dyn Interpolator,
            &SparseMask<'_>,
        ) -> Result<Vec<HeldOut>, InterpError>
        + Sync,
    ) -> Result<Choice, InterpError> {
        let near = near_label(input)?;
        let compact = Compact::of(&input.on(input.mask, &near))?;
        let aligned_apart = pieces_apart(&compact);
        let ruled_out = |c: &dyn Interpolator| aligned_apart && c.name() == "shape-aligned";
        // The candidates run side by side: each one's runs on the compact
        // stack are too small to keep every core busy on their own.
        let runs: Vec<Option<Result<Vec<HeldOut>, InterpError>>> = candidates()
            .par_iter()
            .map(|c| {
                (!ruled_out(c.as_ref())).then(|| {
                    let stacked = c.for_stack(input.axis, &compact.real)?;
                    held_out(&compact, stacked.as_deref().unwrap_or(c.as_ref()), input)
                })
            })
            .collect();
        let shows: Vec<bool> = (0..compact.real.len())
            .map(|p| compact.truth(p).iter().any(|&x| x))
            .collect();
        if alone_across(&compact.real, &shows, ALONE_COPY_GAP) {
            return Ok(Choice {
                index: position_of(Nearest.name()),
                scores: Vec::new(),
                held: Vec::new(),
                compact,
                thin: false,
                ranked: None,
                few: false,
            });
        }
        // Kept: the held-out slices beside one that shows the structure (what
        // the image method learns its fit from); scored: those between two
        // that show it ([`interior`]).
        let mut scores = Vec::new();
        let mut preds = Vec::new();
        for run in runs {
            let Some(held) = run else {
                // Ruled out (`shape-aligned` on pieces apart): never chosen.
                scores.push(f64::NEG_INFINITY);
                preds.push(Vec::new());
                continue;
            };
            let mut held = held?;
            held.retain(|h| shows[h.pos - 1] || shows[h.pos + 1]);
            scores.push(compact.pooled_dice(held.iter().filter(|h| interior(&shows, h.pos))));
            preds.push(held);
        }
        // Counted on the stack, not on what was held out, so that `rank`
        // (half the slices held out) decides as `choose` does.
        let telling = (1..shows.len().saturating_sub(1))
            .filter(|&p| interior(&shows, p))
            .count();
        let few = telling < FEW_HELD_OUT && drifting_gaps(input)?.is_empty();
        if few && ends_inside(&shows) {
            let index = position_of(ShapeArea::default().name());
            return Ok(Choice {
                index,
                held: preds.swap_remove(index),
                scores: Vec::new(),
                compact,
                thin: true,
                ranked: None,
                few: true,
            });
        }
        if telling == 0 || preds.iter().all(Vec::is_empty) {
            // Two drawn slices: nothing to hold out (see `two_slices`),
            // and `fill` fades the outlines in place if they jump.
            return Ok(Choice {
                index: two_slices(input, self.on_stack)?,
                scores: Vec::new(),
                held: Vec::new(),
                compact,
                thin: false,
                ranked: None,
                few: false,
            });
        }
        let ranked = match self.extrapolated(&compact, input, &scores)? {
            Some(errors) => preferred(&errors.iter().map(|e| -e).collect::<Vec<_>>()),
            None => preferred(&scores),
        };
        let area = position_of(ShapeArea::default().name());
        let (index, ranked) = if few && ranked != area {
            // See `FEW_HELD_OUT`; the pick is kept for the image method.
            let held = std::mem::take(&mut preds[ranked]);
            (area, Some((ranked, held)))
        } else {
            (ranked, None)
        };
        let held = preds.swap_remove(index);
        Ok(Choice {
            index,
            scores,
            held,
            compact,
            thin: false,
            ranked,
            few,
        })
    }
}

/// Held-out errors within this share of the best one are too close for the
/// leave-one-out at twice the gap to rank: they are carried to the real gap
/// (see the module docs).
pub const CLOSE: f64 = 0.1;

/// Drawn slices needed to hold out across four times the gap (two kept
/// slices on each side of a held-out one, in at least two places).
const FOR_FOUR_GAPS: usize = 9;

impl ShapeAuto {
    /// The candidates' held-out errors extrapolated to the tracer's own gap,
    /// when the leave-one-out at twice the gap leaves two or more of them
    /// within [`CLOSE`] of the best; `None` otherwise (or with too few drawn
    /// slices). Non-contenders get an infinite error.
    ///
    /// The leave-one-out predicts a drawn slice across twice the tracer's gap,
    /// and which method is best can change with the gap: on fragmented masks
    /// (the T1 k-means classes of the benchmark) copying the nearest slice or
    /// plain blending, behind `shape-aligned` across twice the gap, is ahead
    /// across the gap itself. So the close contenders also predict across four
    /// times the gap (every fourth drawn slice kept, the slices halfway
    /// between scored), and each one's error `e` is carried back towards the
    /// real gap by half the power law through the two spans,
    /// `e(2) · √(e(2) / e(4))` (kept at `e(2)` where the error does not grow
    /// with the span). The whole power law, `e(2)² / e(4)`, trusted the ratio
    /// of two noisy errors too far (stardist's nuclei, `docs/interpolation.md`).
    fn extrapolated(
        &self,
        compact: &Compact,
        input: &SparseMask<'_>,
        scores: &[f64],
    ) -> Result<Option<Vec<f64>>, InterpError> {
        let e2: Vec<f64> = scores.iter().map(|s| 1.0 - s).collect();
        let best = e2.iter().copied().fold(f64::INFINITY, f64::min);
        let close: Vec<bool> = e2.iter().map(|&e| e <= best * (1.0 + CLOSE)).collect();
        if close.iter().filter(|&&c| c).count() < 2 || compact.real.len() < FOR_FOUR_GAPS {
            return Ok(None);
        }
        let runs: Vec<Result<Option<f64>, InterpError>> = candidates()
            .par_iter()
            .zip(&close)
            .map(|(c, &close)| {
                if !close {
                    return Ok(None);
                }
                let stacked = c.for_stack(input.axis, &compact.real)?;
                let held = compact
                    .held_out_to_extrapolate(stacked.as_deref().unwrap_or(c.as_ref()), input)?;
                if held.is_empty() {
                    return Ok(None);
                }
                Ok(Some(1.0 - compact.pooled_dice(&held)))
            })
            .collect();
        let mut out = Vec::with_capacity(e2.len());
        for ((run, &e), &close) in runs.into_iter().zip(&e2).zip(&close) {
            out.push(match (run?, close) {
                (Some(e4), true) if e4 > e => e * (e / e4).sqrt(),
                (Some(_), true) => e,
                (None, true) => return Ok(None),
                (_, false) => f64::INFINITY,
            });
        }
        Ok(Some(out))
    }
}

/// Pieces (8-connected) a drawn slice of the label shows on average from
/// which the tracing is a field of pieces ([`field_of_pieces`]): pieces
/// that join and split from one drawn slice to the next, so that the
/// tracing does not say they are apart.
pub const MANY_PIECES: f64 = 10.0;

/// Pieces (8-connected) a drawn slice of the label shows on average from
/// which, drawn [`WIDE_GAP`] or more slices apart, they are not matched
/// one to one across a gap ([`pieces_apart`]). Lower than [`MANY_PIECES`]:
/// pieces need not join to lose their partners across a wide gap, they
/// only have to appear and vanish or fold between drawn slices. The MNI
/// template's white matter (2–22 pieces a slice, 7.0–7.5 on average at
/// every k) is such a tracing: at k = 6 and 7 the leave-one-out ranked
/// `shape-aligned` first (0.6578 against `shape-area`'s 0.6542 at k = 6),
/// which lost on the real slices to `shape-area` and `shape-based`
/// (0.8543 against 0.8638 and 0.8617). With 6 here `shape-auto` on it went
/// at k = 6 / 7 / 8 from 0.8543 / 0.8373 / 0.8227 to 0.8617 / 0.8429 /
/// 0.8260 (whole volume +0.003 to +0.007), stardist's nuclei (8.8 pieces)
/// at k = 8 from 0.7107 to 0.7075 (`nearest` 0.6943), and nothing else on
/// the benchmark moved; the grey matter (5.5 pieces) keeps `shape-aligned`
/// among its candidates, which it does not choose past k = 1.
pub const UNMATCHED_PIECES: f64 = 6.0;

/// Slices between drawn ones (the median gap) from which the pieces of a
/// field no longer correspond from one drawn slice to the next
/// ([`pieces_apart`]).
pub const WIDE_GAP: usize = 3;

/// Whether `shape-aligned` is ruled out: the drawn slices that show the
/// label hold [`UNMATCHED_PIECES`] or more pieces on average and lie
/// [`WIDE_GAP`] or more slices apart. `shape-aligned` matches each piece
/// with one on the next drawn slice and caps the rest; across such gaps
/// the pieces of a folded ribbon or a porous class do not correspond, and
/// the leave-one-out, which measures across twice the gap, where nothing
/// corresponds for any method (held-out Dice 0.05–0.35), still ranks it
/// first. On the T1 k-means classes of the benchmark (13–37 pieces per
/// slice, every k from 1 to 9 measured) it lost to `shape-based` or
/// `nearest` on every class at k ≥ 5 (by 0.010–0.047) and on five of six
/// at k = 2–4 (by 0.010–0.033), won only at k = 1 (four of six, by
/// 0.012–0.036) and on class 3 at k = 3 (by 0.011). Ruled out from a gap
/// of 3 (k ≥ 2) instead of 6, the classes' mean at k = 2 / 3 / 4 went from
/// 0.6827 / 0.6589 / 0.6292 to 0.6949 / 0.6607 / 0.6375, and the masks
/// where `shape-auto` fell below the best shape anchor from 13 to 6 of
/// 54. The held-out benchmark names the same failure: many pieces per
/// slice, where plain blending, copying or ITK's morphological
/// interpolation win.
pub fn pieces_apart(compact: &Compact) -> bool {
    median_gap(&compact.real).is_some_and(|g| g >= WIDE_GAP)
        && drawn_pieces(compact) >= UNMATCHED_PIECES
}

/// Whether the drawn slices of a compact stack are a field of pieces
/// ([`field_of_pieces`]).
pub fn drawn_field(compact: &Compact) -> bool {
    drawn_pieces(compact) >= MANY_PIECES
}

/// Mean pieces per drawn slice of a compact stack ([`mean_pieces`]).
fn drawn_pieces(compact: &Compact) -> f64 {
    let g = compact.mask.geometry();
    let (a, b) = compact.axis.in_plane();
    let slices: Vec<Vec<bool>> = (0..compact.real.len()).map(|p| compact.truth(p)).collect();
    mean_pieces(&slices, g.dims[a], g.dims[b])
}

/// Whether drawn `slices` (row-major, `width` × `height`) are a field of
/// pieces: [`MANY_PIECES`] or more separate pieces (8-connected) on average
/// on the slices that show the label. Held out across twice the gap, the
/// pieces of such a tracing no longer correspond for any method, so what
/// the held-out slices say is weak: the advice ([`crate::advise`]) does not
/// learn its rates from them, and the image method's whole-box walk does
/// not keep its pieces apart.
pub fn field_of_pieces(slices: &[Vec<bool>], width: usize, height: usize) -> bool {
    mean_pieces(slices, width, height) >= MANY_PIECES
}

/// Mean separate pieces (8-connected) on the `slices` (row-major, `width`
/// × `height`) that show the label; 0 where none does.
fn mean_pieces(slices: &[Vec<bool>], width: usize, height: usize) -> f64 {
    let (mut pieces, mut shown) = (0usize, 0usize);
    for slice in slices.iter().filter(|s| s.iter().any(|&x| x)) {
        pieces += label_2d(slice, width, height, Connectivity::Full).1.len();
        shown += 1;
    }
    if shown == 0 {
        0.0
    } else {
        pieces as f64 / shown as f64
    }
}

/// `input` interpolated by candidate `index` of [`candidates`], with the
/// gaps across which the outline jumps ([`jumping_gaps`]) filled by each
/// outline fading in place ([`crate::jump::fade`]) by `fade_jumps`
/// instead: `shape-auto`'s result ([`Fade::Eased`]), and `image-guided`'s
/// shape prior. Leave-one-out runs measure the candidates as they are
/// (`fade_jumps` `None`).
pub fn fill(
    index: usize,
    input: SparseMask<'_>,
    fade_jumps: Option<Fade>,
) -> Result<Mask, InterpError> {
    let mut out = candidates()[index].interpolate(input)?;
    let Some(profile) = fade_jumps else {
        return Ok(out);
    };
    if candidates()[index].name() == Nearest.name() || pole_fill(index, &input)? {
        return Ok(out);
    }
    let plane = Plane::of(&input);
    let map = |d: usize| -> Result<_, InterpError> {
        let slice = input.mask.slice(input.axis, d)?;
        Ok(SdfCache::signed_distance(input.maps, &slice, &plane))
    };
    for i in jumping_gaps(&input)? {
        let (a, b) = (input.drawn[i], input.drawn[i + 1]);
        for (s, slice) in (a + 1..b).zip(fade(&map(a)?, &map(b)?, b - a, profile)) {
            out.set_slice(input.axis, s, &slice)?;
        }
    }
    Ok(out)
}

/// Share of the smaller of two drawn outlines inside the larger below
/// which a tracing of two slices shares next to nothing (`two_slices`).
pub const DISJOINT: f64 = 0.1;

/// Share of the smaller of two drawn outlines inside the larger from which
/// a tracing of two slices is one structure growing or shrinking in place
/// (`two_slices`).
pub const NESTED: f64 = 0.75;

/// The candidate for a tracing with nothing to hold out (two drawn slices
/// near the label): `shape-aligned` where exactly two drawn slices show the
/// structure and their outlines overlap as one outline that moves (the
/// smaller shares from [`APART`] to [`NESTED`] with the larger), share
/// next to nothing (under [`DISJOINT`]: `fill` fades them) or are too
/// large to be a round structure's polar caps
/// (`shape_area::pole_profile_applies`), or on a leave-one-out stack
/// (`on_stack`, where the profile does not apply), `shape-area` otherwise.
///
/// Why: with two drawn slices `shape-area` takes the structure to end half
/// a slice beyond them and bulge between (`shape_area::pole_area`), which
/// the lesions traced on their first and last slice follow: brain2, lung1
/// and breast1 of `interslice bench` (shares 1.00, 0.88 and 0.81) went from
/// 0.676 / 0.771 / 0.536 on the skipped slices with `shape-aligned` to
/// 0.831 / 0.847 / 0.814, and lung2 at k = 9 (share 0.18, which [`fill`]
/// copied: 0.503) to 0.716. Outlines that share nothing give the blend
/// nothing to hold, and each faded where it was traced is as good
/// (brain1 at k ≥ 5, share 0: 0.436 faded, 0.430 with the profile). An
/// outline that moves between the two slices (a tilted tube) is
/// `shape-aligned`'s to follow, and `fill` fades its jumps; the pole
/// profile is not faded over ([`pole_fill`]).
fn two_slices(input: &SparseMask<'_>, on_stack: bool) -> Result<usize, InterpError> {
    let name = match showing_pair(input)? {
        Some(share) if share < DISJOINT || (APART..NESTED).contains(&share) => "shape-aligned",
        Some(_) if !on_stack && pole_profile_applies(input)? => ShapeArea::default().name(),
        _ => "shape-aligned",
    };
    Ok(position_of(name))
}

/// Whether the held-out drawn slice at `pos` of a compact stack tells the
/// candidates apart: both its neighbours show the structure (`shows`).
///
/// Why: a drawn slice next to one without the structure is predicted across
/// the structure's end, twice the tracer's gap wide, and how each candidate
/// ends an object across that span is not how it ends it across the
/// tracer's own gap. A slice whose neighbours both lack the structure is
/// predicted empty by every candidate. On stardist's nuclei as a label
/// volume (`interslice bench`, every nucleus ending between drawn slices),
/// scoring the slices beside an end as well ranked `shape-aligned`'s caps
/// first where `shape-area` wins on the real gaps; scoring the interior
/// slices only took k = 1 / 2 / 3 / 5 from 0.9043 / 0.8392 / 0.7832 /
/// 0.6966 to 0.9099 / 0.8542 / 0.8107 / 0.7049 (k = 4 and 6 −0.002) and
/// changed no other mask.
fn interior(shows: &[bool], pos: usize) -> bool {
    shows[pos - 1] && shows[pos + 1]
}

/// Interior held-out slices (`interior`) below which `shape-area` fills an
/// object that ends inside the traced range (`ends_inside`) whatever the
/// leave-one-out says, unless its outline drifts steadily across a gap
/// ([`drifting_gaps`]: a tilted tube, `shape-aligned`'s to follow).
///
/// Why: an object that ends between drawn slices has its area profile
/// pinned by the drawn slice without it beyond each end (area 0) and the
/// ones that show it, which `shape-area`'s parabola follows (a round
/// nucleus's `A ∝ R² − z²`); one or two held-out slices, predicted across
/// twice the gap, rank the candidates by noise. On stardist's nuclei as a
/// label volume (label-matched Dice on the skipped slices, k = 1–8), with
/// the interior rule: 0 held out 0.9099 / 0.8542 / 0.8107 / 0.7456 /
/// 0.7049 / 0.6444 / 0.5543 / 0.5851; fewer than 3 held out 0.9231 /
/// 0.8794 / 0.8146 / 0.7824 / 0.7176 / 0.6532 / 0.5578 / 0.5811 (before
/// [`ALONE_COPY_GAP`] came down to 7; `shape-area`
/// alone 0.9231 / 0.8785 / 0.8100 / 0.7538 / 0.6820 / 0.6416 / 0.5104 /
/// 0.5246; since `shape-area`'s pole profile keeps to two drawn slices and
/// nothing beyond, k = 5 and 7 are 0.7171 and 0.5495); fewer than 2 between
/// the two.
///
/// A structure traced from its first to its last slice with one or two
/// such slices takes `shape-area` too, for the same reason: one or two
/// held-out slices, each predicted across twice the gap from slices near
/// the structure's ends, rank the candidates by noise. On the AAL
/// structures of the benchmark (deep grey and medial temporal structures
/// traced by hand on a T1, 3–4 drawn slices from k = 4 to 9) the
/// leave-one-out picked `shape-aligned` on one held-out slice where it
/// lost by up to 0.13 (pallidum-l at k = 6–9: 0.7944 / 0.7669 / 0.7103 /
/// 0.6607 → 0.8318 / 0.8325 / 0.8104 / 0.7911; pallidum-r at k = 5–9 +0.011
/// to +0.040, thalamus-l at k = 9 +0.018, amygdala-r at k = 9 +0.016);
/// the family's mean at k = 6 / 7 / 8 / 9 went from 0.8642 / 0.8462 /
/// 0.8224 / 0.7996 to 0.8696 / 0.8530 / 0.8335 / 0.8148. It cost amygdala-l
/// at k = 9 0.022 and lung2 (a CT lesion longer than wide, 3 drawn slices
/// at k = 6 and 7) 0.018 and 0.020, where `shape-aligned` led, and gained
/// lung2 at k = 4 0.025 and brain1 at k = 1 and 3 0.036 and 0.013. The
/// image method keeps the leave-one-out's pick as its prior there
/// ([`Choice::ranked_first`]). With no such slice at all (two drawn slices
/// that show it) the rule for two slices decides (`two_slices`).
pub const FEW_HELD_OUT: usize = 3;

/// Whether a structure shown on the drawn slices of a compact stack as
/// `shows` says shows on two or more of them and ends inside the traced
/// range: a drawn slice without it lies before its first or after its last
/// showing slice. (An object shown on one drawn slice at a time is
/// `shape-aligned`'s cap or [`alone_across`]'s copy.)
fn ends_inside(shows: &[bool]) -> bool {
    let (Some(first), Some(last)) = (
        shows.iter().position(|&x| x),
        shows.iter().rposition(|&x| x),
    ) else {
        return false;
    };
    shows.iter().filter(|&&x| x).count() >= 2 && (first > 0 || last + 1 < shows.len())
}

/// Gap, in slices, from which an object seen on one drawn slice at a time
/// is copied to half the gap (`nearest`) rather than capped.
///
/// Why: nothing held out shows such an object (its neighbours lack it), so
/// leave-one-out cannot rank the candidates, and how far it reaches past
/// its outline is in no tracing. Across a narrow gap `shape-aligned`'s cap
/// (its outline shrinking towards the empty slices) is the better guess;
/// across a wide one the cap ends too soon and a copy to half the gap,
/// which keeps the object's whole outline as far as the tracing leaves it
/// open, loses less. On stardist's nuclei as a label volume (`interslice
/// bench`, label-matched Dice on the skipped slices): k = 6 / 7 / 8 / 9
/// 0.6532 / 0.5329 / 0.5638 / 0.6518 → 0.6666 / 0.5468 / 0.5809 / 0.6873
/// (`nearest` alone 0.6620 / 0.5396 / 0.5790 / 0.6873; at k = 6 the nuclei
/// seen on one drawn slice: 0.636 capped, 0.674 copied, mean per label);
/// at k = 3 and 5 the cap leads (0.835 against `nearest`'s 0.733 at k = 3,
/// 0.742 against 0.723 at k = 5). No other mask of the benchmark has such
/// an object.
/// With an image, such objects walk from a gap one slice narrower
/// (`image::BLIND_WALK_GAP`).
pub const ALONE_COPY_GAP: usize = 7;

/// Whether a structure shown on the drawn slices at `real` as `shows` says
/// shows on no two consecutive ones, and some gap beside a slice that shows
/// it spans `gap` slices or more: an object seen on one drawn slice at a
/// time, across a wide gap.
pub(crate) fn alone_across(real: &[usize], shows: &[bool], gap: usize) -> bool {
    if shows.windows(2).any(|w| w[0] && w[1]) {
        return false;
    }
    real.windows(2)
        .zip(shows.windows(2))
        .any(|(d, s)| (s[0] || s[1]) && d[1] - d[0] >= gap)
}

/// Index of the candidate called `name` in [`candidates`].
fn position_of(name: &str) -> usize {
    candidates()
        .iter()
        .position(|c| c.name() == name)
        .expect("a candidate")
}

/// The share of the smaller outline inside the larger where exactly two
/// drawn slices of `input` show the structure; `None` otherwise.
fn showing_pair(input: &SparseMask<'_>) -> Result<Option<f64>, InterpError> {
    let mut showing = Vec::new();
    for &d in input.drawn {
        let s = input.mask.slice(input.axis, d)?;
        if s.iter().any(|&x| x) {
            showing.push(s);
        }
    }
    let [a, b] = &showing[..] else {
        return Ok(None);
    };
    let (shared, smaller, _) = overlap_counts(a, b);
    Ok(Some(shared as f64 / smaller as f64))
}

/// Whether `fill` with candidate `index` is `shape-area` on the profile of
/// two drawn slices (`shape_area::pole_area`): the whole structure's
/// bulge, which fading across a jump would throw away.
pub fn pole_fill(index: usize, input: &SparseMask<'_>) -> Result<bool, InterpError> {
    Ok(candidates()[index].name() == ShapeArea::default().name() && pole_profile_applies(input)?)
}

/// The candidate with the highest score, a later one only when it beats the
/// one chosen so far by more than [`MARGIN`].
fn preferred(scores: &[f64]) -> usize {
    let mut index = 0;
    for (i, &s) in scores.iter().enumerate().skip(1) {
        if s > scores[index] + MARGIN {
            index = i;
        }
    }
    index
}

/// The drawn slices of `input` within [`AXIS_SLICES`] drawn slices of the
/// first and last that show the label (all of them when none does).
fn near_label(input: &SparseMask<'_>) -> Result<Vec<usize>, InterpError> {
    let d = input.drawn;
    let shown = showing(input)?;
    let (Some(first), Some(last)) = (
        shown.iter().position(|&x| x),
        shown.iter().rposition(|&x| x),
    ) else {
        return Ok(d.to_vec());
    };
    let lo = first.saturating_sub(AXIS_SLICES);
    let hi = (last + AXIS_SLICES).min(d.len() - 1);
    Ok(d[lo..=hi].to_vec())
}

/// The scales `shape-auto`'s confidence is fitted among ([`held_out_scale`]).
const SHAPE_SCALES: [f32; 2] = [1.0, 2.0];

/// The scale `c` of the shape confidence `σ(c · |φ| / τ(δ))`
/// ([`crate::confidence`]) with the least log-loss on the held-out drawn
/// slices of `choice` (a one-parameter Platt scaling, as the image-guided
/// method fits its own), 1 or 2; 1 where nothing that shows the structure
/// was predicted. Why: at `c = 1` the confidence was 0.65 where the result
/// was right 0.88 of the time (the CT lung lesion lung2 at k = 5), so the
/// preview's tint of "wrong one time in four" did not mean that. Why 1 to
/// 2 only: held out across twice the gap, small objects vanish that the
/// real gaps keep (stardist's nuclei at k = 3 fitted below 1 and were
/// called 0.56–0.65 sure where right 0.77–0.96 of the time), and a smooth
/// shape errs no more than on the real gaps while `τ` doubles (an ellipsoid
/// fitted 8 and was called 0.98 sure where right 0.93 of the time: a tint
/// that hides errors). Every fit on the development data that moved off 1
/// gave 2.
fn held_out_scale(choice: &Choice, plane: &Plane) -> f32 {
    let compact = &choice.compact;
    let slices: Vec<(Vec<f32>, Vec<bool>)> = choice
        .held
        .par_iter()
        .filter(|h| h.predicted.iter().any(|&x| x))
        .map(|h| {
            let t = tau(plane, compact.reach(h.pos) as f64);
            let logit = signed_distance(&h.predicted, plane)
                .iter()
                .map(|&d| -d / t)
                .collect();
            (logit, compact.truth(h.pos))
        })
        .collect();
    if slices.is_empty() {
        return 1.0;
    }
    best_scale(&SHAPE_SCALES, slices.iter().map(|(z, t)| (z, t)))
}

impl Interpolator for ShapeAuto {
    fn box_reach(&self) -> BoxReach {
        // The widest of its candidates' (shape-aligned's).
        BoxReach::Drift
    }

    fn name(&self) -> &'static str {
        "shape-auto"
    }

    fn description(&self) -> &'static str {
        "per label, the shape method (aligned, area-held blend, signed-distance blend, nearest copy) that best predicts the drawn slices left out one at a time; no caps past the outermost drawn slices"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        // The candidates' leave-one-out runs and the final run read the
        // same drawn slices: their maps are computed once.
        SdfCache::sharing(input, |input| {
            let index = self.rank(&input)?;
            input.check_cancelled()?;
            fill(index, input, self.fade())
        })
    }

    /// The result with its confidence calibrated on the tracer's own drawn
    /// slices (`held_out_scale`): the same choice and result as
    /// [`ShapeAuto::interpolate`].
    fn interpolate_with_confidence(
        &self,
        input: SparseMask<'_>,
    ) -> Result<(Mask, Volume<f32>), InterpError> {
        input.validate()?;
        SdfCache::sharing(input, |input| {
            let choice = self.choose_on(&input, Compact::held_out_to_rank)?;
            input.check_cancelled()?;
            let mask = fill(choice.index, input, self.fade())?;
            let scale = held_out_scale(&choice, &Plane::of(&input));
            let confidence = shape_confidence(&mask, &input, scale);
            Ok((mask, confidence))
        })
    }

    fn for_stack(
        &self,
        _axis: Axis,
        _real: &[usize],
    ) -> Result<Option<Box<dyn Interpolator>>, InterpError> {
        Ok(Some(Box::new(ShapeAuto { on_stack: true })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Axis, Geometry, LengthUnit, Volume};

    /// Two drawn slices, z = 0 and z = 6, each with a disc `(centre along x,
    /// radius)` in pixels.
    fn two_discs(discs: [(f64, f64); 2]) -> Mask {
        let g = Geometry::new([64, 32, 7], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for (z, (cx, r)) in [0usize, 6].into_iter().zip(discs) {
            for y in 0..32usize {
                for x in 0..64usize {
                    let (dx, dy) = (x as f64 - cx, y as f64 - 15.5);
                    if dx * dx + dy * dy <= r * r {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        m
    }

    /// A 64×64×40 field of `n`×`n` short tubes along z (slices 5–34), each
    /// a piece on every slice it crosses.
    fn field(n: usize) -> Mask {
        let g = Geometry::new([64, 64, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        let step = 64 / n;
        for z in 5..35usize {
            for y in 0..64usize {
                for x in 0..64usize {
                    let (dx, dy) = (
                        (x % step) as f64 - step as f64 / 2.0,
                        (y % step) as f64 - step as f64 / 2.0,
                    );
                    if dx * dx + dy * dy <= 4.0 {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn shape_aligned_is_ruled_out_on_a_field_of_pieces_drawn_far_apart() {
        let aligned_score = |m: &Mask, step: usize| {
            let drawn: Vec<usize> = (5..35).step_by(step).collect();
            ShapeAuto::default()
                .choose(&SparseMask::new(m, Axis::Z, &drawn))
                .unwrap()
                .scores[0]
        };
        // 16 or 9 pieces per slice, drawn `WIDE_GAP` slices apart: ruled
        // out (9 is no field of pieces, but more than `UNMATCHED_PIECES`).
        assert_eq!(aligned_score(&field(4), WIDE_GAP), f64::NEG_INFINITY);
        assert_eq!(aligned_score(&field(3), WIDE_GAP), f64::NEG_INFINITY);
        // The same field drawn closer, or 4 pieces as far apart: held out.
        assert!(aligned_score(&field(4), WIDE_GAP - 1).is_finite());
        assert!(aligned_score(&field(2), WIDE_GAP).is_finite());
    }

    /// A 32 × 32 × `slices` mask holding a disc of radius 6 on slice `z`.
    fn disc_on(slices: usize, z: usize) -> Mask {
        let g = Geometry::new([32, 32, slices], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for y in 0..32usize {
            for x in 0..32usize {
                let (dx, dy) = (x as f64 - 15.5, y as f64 - 15.5);
                if dx * dx + dy * dy <= 36.0 {
                    m.set(x, y, z, true);
                }
            }
        }
        m
    }

    /// A 32 × 32 × 21 mask holding a ball of radius 8 centred on slice 10
    /// (slices 3–17).
    fn ball() -> Mask {
        let g = Geometry::new([32, 32, 21], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut m: Mask = Volume::zeros(g);
        for z in 0..21usize {
            for y in 0..32usize {
                for x in 0..32usize {
                    let (dx, dy, dz) = (x as f64 - 15.5, y as f64 - 15.5, z as f64 - 10.0);
                    if dx * dx + dy * dy + dz * dz <= 64.0 {
                        m.set(x, y, z, true);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn only_slices_between_two_showing_ones_are_scored() {
        // A disc on slice 5 alone, drawn with the empty slices 0 and 10:
        // nothing to score, so the choice is the one for two slices.
        let mut m = disc_on(11, 5);
        let drawn = [0usize, 5, 10];
        let choice = ShapeAuto::default()
            .choose(&SparseMask::new(&m, Axis::Z, &drawn))
            .unwrap();
        assert!(choice.scores.is_empty() && choice.held.is_empty());
        // On slices 5 and 8: each is beside an empty drawn slice, so
        // neither is scored; both are kept for the image method's fit.
        let disc = m.slice(Axis::Z, 5).unwrap();
        m.set_slice(Axis::Z, 8, &disc).unwrap();
        let drawn = [0usize, 5, 8, 10];
        let choice = ShapeAuto::default()
            .choose(&SparseMask::new(&m, Axis::Z, &drawn))
            .unwrap();
        assert!(choice.scores.is_empty());
        assert_eq!(
            choice.held.iter().map(|h| h.pos).collect::<Vec<_>>(),
            [1, 2]
        );
        // A tube on slices 2–10 drawn every other slice: the drawn slices
        // 4, 6 and 8 lie between two that show it, and only they are scored.
        let g = m.geometry().clone();
        let mut tube: Mask = Volume::zeros(Geometry::new([32, 32, 13], g.spacing, g.unit).unwrap());
        for z in 2..=10 {
            tube.set_slice(Axis::Z, z, &disc).unwrap();
        }
        let drawn = [0usize, 2, 4, 6, 8, 10, 12];
        let choice = ShapeAuto::default()
            .choose(&SparseMask::new(&tube, Axis::Z, &drawn))
            .unwrap();
        let kept: Vec<usize> = choice.held.iter().map(|h| drawn[h.pos]).collect();
        assert_eq!(kept, [2, 4, 6, 8, 10]);
        let interior = choice
            .held
            .iter()
            .filter(|h| (4..=8).contains(&drawn[h.pos]));
        assert_eq!(
            choice.scores[choice.index],
            choice.compact.pooled_dice(interior)
        );
        assert_ne!(
            choice.scores[choice.index],
            choice.compact.pooled_dice(&choice.held)
        );
    }

    #[test]
    fn an_object_ending_inside_the_traced_range_with_little_held_out_takes_the_area_profile() {
        let m = ball();
        let chosen = |drawn: &[usize]| {
            let choice = ShapeAuto::default()
                .choose(&SparseMask::new(&m, Axis::Z, drawn))
                .unwrap();
            (candidates()[choice.index].name(), choice.scores.len())
        };
        // Drawn every fourth slice with the empty slices 0 and 20: the ball
        // shows on 4, 8, 12 and 16, two of them between showing ones.
        assert_eq!(
            chosen(&[0, 4, 8, 12, 16, 20]),
            (ShapeArea::default().name(), 0)
        );
        // Traced from its first to its last slice: the leave-one-out decides
        // (held out: 7, 10 and 13).
        let drawn = [3usize, 7, 10, 13, 17];
        let choice = ShapeAuto::default()
            .choose(&SparseMask::new(&m, Axis::Z, &drawn))
            .unwrap();
        assert_eq!(choice.scores.len(), candidates().len());
        assert_eq!(choice.held.len(), 3);
        // Between them, `ends_inside` says which is which.
        assert!(ends_inside(&[false, true, true, false]));
        assert!(!ends_inside(&[true, true, true]));
        assert!(!ends_inside(&[false, true, false]));
    }

    #[test]
    fn a_tube_tilted_against_the_slices_is_followed_not_faded() {
        // Radius 5, 2 pixels a slice along x, slices 5–20, drawn every 3rd
        // slice from 0 (0, 3 and 21, 24 without it).
        let g = Geometry::new([64, 48, 40], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut truth: Mask = Volume::zeros(g);
        for z in 5..=20usize {
            let cx = 10.0 + 2.0 * (z - 5) as f64;
            for y in 0..48usize {
                for x in 0..64usize {
                    let (dx, dy) = (x as f64 - cx, y as f64 - 24.0);
                    truth.set(x, y, z, dx * dx + dy * dy <= 25.0);
                }
            }
        }
        let drawn: Vec<usize> = (0..40).step_by(3).collect();
        let mut sparse: Mask = Volume::zeros(truth.geometry().clone());
        for &d in &drawn {
            sparse
                .set_slice(Axis::Z, d, &truth.slice(Axis::Z, d).unwrap())
                .unwrap();
        }
        let out = ShapeAuto::default()
            .interpolate(SparseMask::new(&sparse, Axis::Z, &drawn))
            .unwrap();
        let (mut both, mut sum) = (0usize, 0usize);
        for z in (5..=20).filter(|z| z % 3 != 0) {
            let (o, t) = (
                out.slice(Axis::Z, z).unwrap(),
                truth.slice(Axis::Z, z).unwrap(),
            );
            both += o.iter().zip(&t).filter(|&(&a, &b)| a && b).count();
            sum += o.iter().chain(&t).filter(|&&x| x).count();
        }
        let dice = 2.0 * both as f64 / sum as f64;
        // Faded in place as jumps, 0.76.
        assert!(dice > 0.88, "Dice {dice:.4} on the skipped slices");
    }

    #[test]
    fn an_object_alone_on_its_drawn_slice_is_copied_across_wide_gaps_only() {
        // A disc on slice 10 alone, between the empty drawn slices 10 - g
        // and 10 + g.
        let mut m = disc_on(21, 10);
        let chosen = |gap: usize| {
            let drawn = [10 - gap, 10, 10 + gap];
            let index = ShapeAuto::default()
                .choose(&SparseMask::new(&m, Axis::Z, &drawn))
                .unwrap()
                .index;
            candidates()[index].name()
        };
        assert_eq!(chosen(ALONE_COPY_GAP), Nearest.name());
        assert_eq!(chosen(10), Nearest.name());
        assert_ne!(chosen(ALONE_COPY_GAP - 1), Nearest.name());
        assert_ne!(chosen(4), Nearest.name());
        // Seen on two drawn slices side by side: the usual choice.
        let disc = m.slice(Axis::Z, 10).unwrap();
        m.set_slice(Axis::Z, 20, &disc).unwrap();
        let drawn = [0usize, 10, 20];
        let choice = ShapeAuto::default()
            .choose(&SparseMask::new(&m, Axis::Z, &drawn))
            .unwrap();
        assert_ne!(candidates()[choice.index].name(), Nearest.name());
    }

    #[test]
    fn gaps_across_which_the_outline_jumps_fade_in_place_and_others_blend() {
        let drawn = [0usize, 6];
        let run = |m: &Mask, drawn: &[usize]| {
            let input = SparseMask::new(m, Axis::Z, drawn);
            (
                jumping_gaps(&input).unwrap(),
                ShapeAuto::default().interpolate(input).unwrap(),
            )
        };
        let area = |m: &Mask, z: usize| m.slice(Axis::Z, z).unwrap().iter().filter(|&&x| x).count();
        // Shifted by 3 pixels (sharing about 0.7): one outline moving.
        let moving = two_discs([(20.0, 6.0), (23.0, 6.0)]);
        let (jumps, out) = run(&moving, &drawn);
        assert!(jumps.is_empty());
        let at = |m: &Mask, z: usize| m.slice(Axis::Z, z).unwrap();
        assert!(at(&out, 3) != at(&moving, 0) && at(&out, 3) != at(&moving, 6));
        // Growing from radius 2 to 10 about one centre (a Dice of 0.08, but
        // the small outline inside the large one): a cone, blended (its
        // wide end is no polar cap: no bulge).
        let cone = two_discs([(30.0, 2.0), (30.0, 10.0)]);
        let (jumps, out) = run(&cone, &drawn);
        assert!(jumps.is_empty());
        assert!(area(&out, 3) > area(&cone, 0) && area(&out, 3) < area(&cone, 6));
        // Shifted by 20 (no overlap): each outline fades in place.
        let far = two_discs([(20.0, 6.0), (40.0, 6.0)]);
        let (jumps, out) = run(&far, &drawn);
        assert_eq!(jumps, vec![0]);
        let plane = Plane::of(&SparseMask::new(&far, Axis::Z, &drawn));
        let sdf = |m: &Mask, z: usize| crate::sdf::signed_distance(&at(m, z), &plane);
        let faded = fade(&sdf(&far, 0), &sdf(&far, 6), 6, Fade::Eased);
        for s in 1..6 {
            assert_eq!(at(&out, s), faded[s - 1], "slice {s}");
        }
        // A drawn-empty slice is no jump: the structure ends there.
        let mut ends = far.clone();
        let (w, h) = ends.slice_shape(Axis::Z);
        ends.set_slice(Axis::Z, 6, &vec![false; w * h]).unwrap();
        assert!(run(&ends, &drawn).0.is_empty());
        // Three drawn slices: only the gap across which the outline jumps
        // fades, the other one is blended (by `shape-aligned`).
        let g = Geometry::new([64, 32, 13], [1.0; 3], LengthUnit::Micrometre).unwrap();
        let mut three: Mask = Volume::zeros(g);
        for (z, cx) in [(0usize, 20.0), (6, 23.0), (12, 43.0)] {
            for y in 0..32usize {
                for x in 0..64usize {
                    let (dx, dy) = (x as f64 - cx, y as f64 - 15.5);
                    if dx * dx + dy * dy <= 36.0 {
                        three.set(x, y, z, true);
                    }
                }
            }
        }
        let input = SparseMask::new(&three, Axis::Z, &[0, 6, 12]);
        assert_eq!(jumping_gaps(&input).unwrap(), vec![1]);
        let out = fill(0, input, Some(Fade::Eased)).unwrap();
        assert!(at(&out, 3) != at(&three, 0) && at(&out, 3) != at(&three, 6));
        let faded = fade(&sdf(&three, 6), &sdf(&three, 12), 6, Fade::Eased);
        for s in 7..12 {
            assert_eq!(at(&out, s), faded[s - 7], "slice {s}");
        }
        // A field of pieces never fades for jumping.
        let tubes = field(4);
        let mut shifted = tubes.clone();
        let (w, h) = tubes.slice_shape(Axis::Z);
        let mut moved = vec![false; w * h];
        for (i, &v) in tubes.slice(Axis::Z, 15).unwrap().iter().enumerate() {
            moved[(i + 8) % (w * h)] = v;
        }
        shifted.set_slice(Axis::Z, 15, &moved).unwrap();
        let input = SparseMask::new(&shifted, Axis::Z, &[5, 15, 25, 34]);
        assert!(jumping_gaps(&input).unwrap().is_empty());
    }
}
