//! `image-guided`: interpolation that reads the intensity volume, and learns
//! from the tracer's own drawn slices how far to trust it.
//!
//! Per label:
//! 1. **Shape prior.** [`ShapeAuto`]'s leave-one-out choice of shape method
//!    interpolates the label, copying across the gaps where the outline
//!    jumps ([`fill`]); its signed distance on each skipped slice is
//!    the prior.
//! 2. **How the boundary sits on the image.** The intensities just inside
//!    and just outside the tracing on the drawn slices give a log-likelihood
//!    ratio per intensity ([`model::IntensityModel`]).
//! 3. **Fusion** per skipped slice ([`fuse`](mod@fuse)): prior logit plus weighted
//!    likelihood, smoothed along image edges (a random-walker-like
//!    regularisation, Grady 2006), in a band around the prior, objects kept
//!    apart. This is the idea of Biomedisa's "smart interpolation" (Lösel et
//!    al. 2020: a random walk seeded by the drawn slices) made local to each
//!    skipped slice and anchored to the shape, so it runs in about the time of
//!    the shape method.
//! 4. **Leave-one-out.** Every interior drawn slice is predicted from its
//!    drawn neighbours ([`crate::loo`]) by the prior alone and by the fusion
//!    with each weight `w` and smoothing `λ` of a small grid; the pair with
//!    the best pooled Dice is kept, and the image is used only when it beats
//!    the shape alone by more than [`MARGIN`]. Where the image is noise or the
//!    contrast does not follow the tracing, `w = 0`: the result is the shape
//!    prior, bit for bit. Where no held-out slice shows the label (a lesion
//!    traced on its first and last slice), neighbouring drawn slices that
//!    show it predict each other by a copy of their outlines instead
//!    (`cross_cases`), on a clear edge only ([`EDGE_SEPARATION`]).
//! 5. **The walk.** Where the fusion finds no use for the image, a 3D random
//!    walker may still follow it ([`walk`](mod@walk), Grady 2006: the drawn
//!    slices as seeds, as in Biomedisa's smart interpolation). It runs in the
//!    band around the shape prior only (the prior seeds the rest), so it
//!    solves a thin shell instead of the label's box, and its decision is
//!    kept apart per object as the fusion's is. It replaces the fusion where
//!    it predicts the held-out slices of one leave-one-out run (every other
//!    interior drawn slice erased from the volume) clearly better
//!    ([`WALK_RHO`], a bar for narrow gaps only). Where that band walk comes
//!    close and the gaps are wider than one slice either side (or the
//!    tracing is a field of pieces), the walk on
//!    the label's whole box is tried too ([`Walk::Box`]): it follows the
//!    image past the prior's band, which thin intensity-defined structures
//!    need.
//!
//! Invariants are those of the trait: only skipped slices inside the drawn
//! range are changed (drawn slices are copied, drawn-empty slices stay
//! empty, nothing appears past the outermost drawn slices), distances are
//! physical (any axis, anisotropic spacing), and neither the fusion nor the
//! walk joins objects that the prior keeps apart.
pub mod conditioned;
pub mod fuse;
pub mod model;
pub mod walk;

use crate::auto::{Choice, ShapeAuto, alone_across, drawn_field, fill, pole_fill};
use crate::confidence::{best_scale, shape_confidence, sigmoid};
use crate::crop::{BoxReach, DrawnSlice, LabelBox, drawn_planes};
use crate::jump::Fade;
use crate::jump::jumping_gaps;
use crate::loo::{overlap, pooled_dice};
use crate::sdf::{FAR, signed_distance};
use crate::slices::{Plane, assemble, median_gap, showing, shows_on, to_nearest_drawn};
use crate::{InterpError, Interpolator, SparseMask};
pub use conditioned::Conditioned;
use fuse::{Params, band, fuse, separate, tau};
use interslice_core::{AnyVolume, Axis, Mask, Volume};
use model::{IntensityModel, blur};
use rayon::prelude::*;
use std::sync::Arc;
use walk::RandomWalk;

/// Pooled Dice the image must gain over the shape alone (leave-one-out) to be used.
pub const MARGIN: f64 = 0.001;

/// The held-out slices lie about twice as far from their drawn neighbours
/// as the skipped slices of the real run, and the shape's error shrinks with
/// that distance faster than the fusion's: the image is used only when its
/// held-out error is below `RHO` times the shape's. Set on the development
/// data (`interslice bench`, the table in `docs/interpolation.md`): on
/// stardist's nuclei at k = 1 the image cuts the held-out error to 0.79 of
/// the shape's yet loses 0.05 Dice on the real skipped slices, one slice
/// from a drawn one, where the shape is nearly exact; at 0.75 the T1
/// classes gain 0.09–0.26 and stardist's nuclei 0.05–0.06 at k ≥ 5, where
/// 0.4 kept the image off both. (Two other rules were measured and
/// dropped: extrapolating each fusion's error to the real distance from a
/// second leave-one-out across twice the gap, and letting a whole-slice
/// likelihood add objects the prior lacks; both lost to this bar on the
/// development data, the second by false objects in the MR lesions.)
pub const RHO: f64 = 0.75;

/// The image's floor must lie below this share of the shape's held-out
/// error for the fusion to be used. The floor is the fusion's error where
/// the prior is already right: each held-out slice fused from its own
/// tracing's signed distance (at the confidence the prior has half as far
/// out, about the real skipped slices' distance). A shape blend's error
/// shrinks at least linearly as the distance to the drawn slices halves
/// (from the held-out slices' to the real ones'), so the shape is expected
/// below half its held-out error there; a fusion that moves a right
/// boundary by that much can only lose. On the noisy phantom's cell traced
/// every 8th slice (`image::on_the_noisy_phantom_...`) the held-out error
/// of `shape-area` is 0.046, the fusion's 0.027 (it passes [`RHO`]), its
/// floor 0.024: the image was used and cost 0.013 on the skipped slices
/// (0.990 → 0.977). This share holds for a field of pieces
/// ([`Plan::field`]): a quarter instead of a half took 0.02–0.09 from the
/// T1 classes, whose pieces' errors do not shrink with the distance as a
/// smooth shape's do, and 0.4 took 0.12–0.14 from class 4 at k = 4–6.
/// Elsewhere see [`SHAPE_FLOOR_SHARE`].
pub const FLOOR_SHARE: f64 = 0.5;

/// [`FLOOR_SHARE`] where the drawn slices are not a field of pieces.
///
/// Why lower: a smooth boundary blended between two drawn slices strays
/// from the truth most in the middle of the gap and little next to either
/// slice (for a boundary that bends smoothly, as `δ (G − δ)` at `δ` slices
/// into a gap of `G`), so its error over the real skipped slices falls to
/// well below half its error held out across twice the gap: to a sixth
/// were it all bending, to a half were it all a steady drift. On
/// stardist's nuclei as one mask at k = 2 the fusion's floor was 0.41 of
/// the shape's held-out error (0.139 against 0.336); the fusion, used,
/// scored 0.8539 on the skipped slices against the shape's 0.8826 (an
/// error of 0.117, 0.35 of the held-out one). Set on `interslice bench`:
/// at 0.4 and 0.35 that mask at k = 2 and phantom 2's cell at k = 9 keep
/// the shape (0.8539 → 0.8826, 0.9873 → 0.9931) and nothing else changes;
/// at 0.3 the phantom nuclei at k = 3 (−0.002, −0.005) and stardist's
/// nuclei at k = 5 and 6 (0.8001 → 0.7911, 0.7872 → 0.7645, floor shares
/// 0.315 and below) lose the image where it helped.
pub const SHAPE_FLOOR_SHARE: f64 = 0.35;

/// The bar of [`RHO`] for the random walk ([`Plan::walk`]): its held-out
/// error must be below this times the fusion's (or prior's). Held out at
/// twice the real gap, the walk loses more than the shape does (on thin
/// structures it collapses: T1 class 3 at k = 3 scores 0.17 on the held-out
/// slices where the whole-box walk scores 0.69 on the real gaps), so
/// the walk is chosen only where it wins clearly. Set on the development
/// data (`interslice bench`): stardist's nuclei at k = 1 (error ratio
/// 0.84) do not pass, where the walk would lose 0.017 one slice from a
/// drawn one.
///
/// The bar holds only where every gap between the label's drawn slices is
/// narrower than [`BOX_WALK_MIN_GAP`] and the tracing is not a field of
/// pieces (there see [`BOX_WALK_MIN_GAP`]). Across wider gaps the held-out run
/// understates the walk (its slices lie twice as far out, where the walk
/// collapses on thin structures before the shape does), and a walk that
/// beats the fusion there by [`MARGIN`] at all won on every real gap of
/// the development data: T1 class 1 at k = 5 and 9 (error ratios 0.81 and
/// 0.86; 0.965 → 0.972 and 0.954 → 0.963 on the skipped slices) and class 2
/// at k = 5 (0.85; 0.657 → 0.735), with no case there where it lost.
pub const WALK_RHO: f64 = 0.8;

/// The whole-box walk ([`Walk::Box`]) is tried only where the band walk's
/// held-out error is at most this times the fusion's (or prior's). The
/// box costs 5–20 times the band (2–7 s on the 256×256×60 and 197×233×189
/// phantoms of `interslice bench --speed`, where the band walk's error is
/// 1.6–9 times the fusion's); on the development data the box walk won
/// only where the band walk had come within 1.03 of the fusion.
pub const BOX_WALK_GATE: f64 = 1.25;

/// The fusion a walk is compared with is fitted again on the other
/// held-out slices (those of the run that keeps the odd positions) where
/// there are at least this many of them; with fewer the plan's own fit is
/// used.
///
/// Why: the walk is scored on the slices its one leave-one-out run erased,
/// and the plan's fusion was chosen among [`GRID`]'s eight `(w, λ)` on
/// those same slices, its scale `τ` fitted on them too, while the walk
/// fits nothing. The in-sample score is the best of eight on few slices,
/// and that optimism decided: on T1 class 1 at k = 6–8 (8–10 drawn
/// slices, 3–4 held out per run) the fusion scored 0.953–0.956 in sample
/// and 0.934–0.939 fitted on the other slices, the box walk 0.945–0.953;
/// compared with the refitted fusion the box walk is taken and is ahead on
/// the skipped slices, 0.9669 / 0.9651 / 0.9619 → 0.9715 / 0.9696 /
/// 0.9662 (level with the walker anchor), and no other mask of the
/// benchmark changed. Fitted on one slice (lung2 at k = 3) the refit is
/// noise: the band walk was then taken and lost 0.011. Where the plan
/// keeps the shape alone the comparison is already fair (nothing fitted)
/// and nothing is refitted: a refit there that took the image scored below
/// the shape and let the band walk into stardist's nuclei at k = 1, which
/// lost 0.003.
pub const REFIT_MIN_CASES: usize = 3;

/// The whole-box walk is tried only where two drawn slices of the label
/// lie at least this far apart (some skipped slice two or more slices from
/// a drawn one). Next to a drawn slice the shape is nearly exact and what
/// decides is where the tracer puts the boundary on the image, which the
/// fusion learns and the walk does not: on stardist's nuclei at k = 1 the
/// box walk clears its bar on the held-out slices (error ratio 0.73) and
/// loses 0.019 on the real ones.
///
/// A field of pieces ([`crate::auto::field_of_pieces`]) counts as wide at
/// any gap, for this and for [`WALK_RHO`]: its pieces do not correspond
/// from one drawn slice to the next, so the shape is not nearly exact next
/// to a drawn slice, and held out across twice the gap its thin pieces
/// collapse in the walk as they do across wide gaps. On the T1 k-means
/// classes at k = 1 and 2 the walk then took classes 1, 2 and 3 (before
/// `walk::undiluted` and [`Plan::field`]; class 3:
/// 0.6926 → 0.7736 and 0.6623 → 0.7276 on the skipped slices, level with
/// the walker anchor's 0.7919 and 0.7411; class 1 +0.004 and +0.006) and
/// lost nowhere (class 2 at k = 2: −0.0001), for 0.5–0.7 s more per class
/// on their 128 × 128 × 62 volume.
pub const BOX_WALK_MIN_GAP: usize = 4;

/// Where nothing between the drawn slices can be held out (two drawn
/// slices show the label, or one: [`BLIND_WALK_GAP`]), the image is read
/// only when intensity alone tells the pixels just inside the tracing from
/// those just outside with this area under the ROC curve
/// ([`IntensityModel::separation`]): the traced boundary is an edge in the
/// image. Where contrast is weak the fusion and the walk leak and the
/// shape is kept.
///
/// Two neighbouring drawn slices that show the label predict each other
/// (`cross_cases`) and the fusion is fitted on that. Only past this
/// bar: two held-out slices are little evidence, and a copy is a weak
/// shape to beat. On a sheared ball whose image is noise ten times the
/// contrast (separation 0.66) the fusion mended the two copies (0.52 →
/// 0.72) and lost 0.013 to the shape's blend on the skipped slices; on
/// brain2 (0.70) it gained 0.003.
///
/// Where the fusion finds no use for the image (or one drawn slice shows
/// the label), the whole-box walk ([`Walk::Box`]) is used past this bar.
/// On the development data's tracings of two slices (`interslice bench`)
/// the fusion took every one that passes: lung1, breast1 and brain1 at
/// k ≥ 5 (see `cross_cases`; the walk there had 0.902, 0.656 and
/// 0.488 against shape-aligned's 0.771, 0.536 and 0.436, and brain2 at
/// 0.70 would have lost with it, 0.441 against 0.676).
///
/// Not the walk where the prior is `shape-area`'s profile of two drawn
/// slices (`crate::auto::pole_fill`: the structure ends half a slice
/// beyond them and bulges between): walking from two slices, the walk
/// knows nothing of the bulk between them, and raised to that prior's area
/// where diluted (`walk::undiluted`) it lost to the profile on lung1
/// (0.822 against 0.847) and on a ball with a clean edge (0.774 against
/// 0.848). The fusion, in a band around that profile, keeps its bulk.
pub const EDGE_SEPARATION: f64 = 0.9;

/// Where nothing held out shows the label and no two consecutive drawn
/// slices both show it (an object seen on one drawn slice, whose
/// neighbours both lack it: a small nucleus of a label volume), the
/// whole-box walk is used, whatever the edge, once some gap beside a drawn
/// slice that shows the label spans at least this many slices. How far
/// such an object reaches past its one outline is in no tracing: the shape
/// methods guess it (a copy to half the gap, a cap), and the wider the gap
/// the worse the guess, while the walk stops where the image does (and,
/// on an image without an edge, fades towards the empty drawn slices as
/// the guesses do). The walk decides past where the shape prior ends too
/// (`decide_slices`): the guess is what it replaces.
///
/// On stardist's nuclei as a label volume (`interslice bench`,
/// label-matched Dice on the skipped slices) at k = 9 the 49 nuclei seen
/// on one drawn slice went from 0.66 (the shape) to 0.75, level with the
/// walker anchor, the walk winning at every edge separation from 0.6 up.
/// The whole mask at k = 4 / 5 / 6 / 7 / 8 / 9: 0.8071 / 0.7545 / 0.7130 /
/// 0.5336 / 0.5800 / 0.7410 with the gap at 7 and the walk kept inside
/// the prior's slices, 0.8071 / 0.7570 / 0.7249 / 0.5454 / 0.5913 / 0.7405
/// with the gap at 6 and the walk past them (the walker anchor 0.8299 /
/// 0.7651 / 0.7335 / 0.5493 / 0.5918 / 0.7410: what is left between them
/// is in the nuclei seen on two drawn slices, `THIN_SHAPE_GAP`). At 5
/// k = 4 lost to the shape (0.8071 → 0.8039); at k = 3 (a gap of 4) the
/// 3 such nuclei lost 0.08 to the walk (0.83 → 0.75).
///
/// One slice below `shape-auto`'s copy of such objects
/// ([`crate::auto::ALONE_COPY_GAP`]): at a gap of 6 the shape caps them,
/// and the walk follows the image past the cap.
pub const BLIND_WALK_GAP: usize = 6;

/// Edge contrast ([`model::edge_contrast`]) from which a label whose
/// outline jumps across some gap between drawn slices ([`jumping_gaps`]:
/// two outlines that share little of the smaller, which the shape fades
/// each in place) takes the whole-box walk where the fusion and the
/// leave-one-out's walk found no use for the image. The bar is
/// [`EDGE_CONTRAST`]'s: an edge the walk can follow voxel to voxel.
///
/// Why without the leave-one-out's say: held out across twice the gap,
/// the outline jumps for every method and the held-out slices score next
/// to nothing (brain1 at k = 1, 6.5 mm slices: two held out, the one in
/// the walk's run 0 for the prior, the fusion and the walk alike), so the
/// tracing cannot rank the walk, and the shape there is a guess of where
/// outlines go that no tracing shows. On the development data
/// (`interslice bench`) this moves only brain1 at k = 1 (edge contrast
/// 9.2): 0.6342 → 0.6984 on the skipped slices, level with the walker
/// anchor; walking only the gaps that jump, the prior keeping the rest,
/// gave 0.6715. At k = 2–4 the fusion or the walk is already taken.
///
/// Only where the blurred image separates the two sides of the drawn
/// outlines by [`WEAK_SEPARATION`] or more (brain1: 0.92–0.94): the AAL
/// hippocampus, a curved structure whose outlines share under 40 % across
/// gaps of 5–8 slices, has a contrast of about 4 on the low-noise colin27
/// T1 but a separation of 0.70, and the walk lost 0.019 and 0.016 to the
/// shape at k = 4 and 7 (hippocampus-r: 0.8418 / 0.8005 against 0.8611 /
/// 0.8163).
pub const JUMP_WALK_CONTRAST: f64 = EDGE_CONTRAST;

/// Contrast of the traced boundary over the image's noise
/// ([`model::edge_contrast`]: the mean step across the tracing over the
/// median step between neighbours on one side, on the drawn slices as they
/// are) from which an object `shape-auto` took by rule on too little held
/// out walks across wide gaps ([`THIN_SHAPE_GAP`]).
///
/// Why not the blurred image's [`IntensityModel::separation`], as where
/// nothing is held out ([`EDGE_SEPARATION`]): the walk's edge weights read
/// the image as it is, voxel to voxel. Where noise is independent from one
/// voxel to the next, a blur separates the two sides long before the walk
/// can follow the edge: on a ball drawn every 4th–6th slice whose image
/// carries such noise, the walk lost 0.05–0.08 to the shape at
/// separations of 0.98–0.99 (contrasts of 1.3–1.6), came level at a
/// contrast of 2.2 and won from 2.4 up (0.89–1.00 against 0.86).
/// Microscope images are smooth at the pixel scale, and there the contrast
/// ranks where the walk helps: on stardist's nuclei as a label volume
/// (`interslice bench`, label-matched Dice on the skipped slices) at k = 3 /
/// 4 / 5 / 6 / 7 / 8 0.8221 / 0.7990 / 0.7519 / 0.7020 / 0.5299 / 0.5785 →
/// 0.8342 / 0.8071 / 0.7545 / 0.7052 / 0.5336 / 0.5800 against the
/// separation's gate, with 2.5 and 3.0 between the two. Where the shape is
/// poor (an object seen on one drawn slice, capped) the walk wins even on
/// noise, and the separation's gate is kept there.
///
/// 3, not 2: the nucleus of the 48³ noisy phantom cell (noise 10 % of full
/// scale, independent per voxel, blur σ 0.7) as a label of its label
/// volume, drawn every 6th slice, shows on three drawn slices and ends
/// between them; its contrast of about 2.7 let it walk, and the walk lost
/// 0.09 to the shape on the skipped slices (0.8226 against 0.9131; `study
/// --image`, `crates/cli/tests/integration/study_cli.rs`). At 3 it keeps
/// the shape (0.9078); stardist's nuclei as a label volume lost 0.001–0.006
/// at k = 3–7 (k = 5: 0.7593 → 0.7555) and gained 0.002 at k = 8.
pub const EDGE_CONTRAST: f64 = 3.0;

/// Median gap, in slices, across which the shape `shape-auto` took by rule
/// on too little held out (`auto::Choice::thin`: an object that ends inside
/// the traced range, seen on few drawn slices) is kept without the image.
///
/// Why: what is held out for such an object lies beside its ends, twice
/// the tracer's gap from its neighbours, where the shape's caps are poor
/// and the image mends them, so the fit trusts the image more than the
/// tracer's own gap warrants. Across narrow gaps the shape's area profile
/// is close and the fit only perturbs it; across wide ones the image's
/// help outweighs that. On stardist's nuclei as a label volume
/// (`interslice bench`, label-matched Dice on the skipped slices), the
/// shape kept for every such label: k = 1 / 2 / 3 / 4 / 5 0.9094 / 0.8539
/// / 0.8145 / 0.7897 / 0.7424 → 0.9231 / 0.8790 / 0.8146 / 0.7806 /
/// 0.7247 (the shape alone 0.9231 / 0.8794 / 0.8146 / 0.7824 / 0.7171).
///
/// Across wider gaps such a label takes the whole-box walk where its drawn
/// outlines lie on an edge the walk can follow ([`EDGE_CONTRAST`]) and
/// keeps the shape otherwise. With the gate on the blurred separation at
/// [`EDGE_SEPARATION`] instead: k = 3 / 4 / 5 / 6 / 7 / 8 0.8145 / 0.7897
/// / 0.7424 / 0.6756 / 0.5361 / 0.5496 → 0.8221 / 0.7990 / 0.7519 / 0.7020
/// / 0.5299 / 0.5785 (the fit instead of the shape below the edge: 0.8220
/// / 0.8016 / 0.7504 / 0.7023 / 0.5350 / 0.5713, but on a ball whose image
/// is noise the fit lost 0.021 to the shape). Walking
/// every such label gained more there (0.8375 / 0.8090 / 0.7630 / 0.7146 /
/// 0.5386 / 0.5806), but on that ball the walk lost to the shape (0.74
/// against 0.86 at edge separations 0.58 and 0.76; 0.78 at 0.945, where
/// the noise is independent from voxel to voxel, unlike a microscope's
/// blur).
pub const THIN_SHAPE_GAP: usize = 3;

/// Separation of the two sides of the drawn outlines on the blurred image
/// ([`IntensityModel::separation`]) below which the image is too weak to
/// walk on or to read on a few slices: a structure `shape-auto` fills by
/// rule on too few held-out slices (`auto::Choice::few`: fewer than three
/// between two drawn slices that show it) keeps the shape, and a label
/// that is not a field of pieces is not walked (`try_walk`).
///
/// Why no walk: held out across twice the gap, a walk on such an image
/// that beats the fusion (or the shape) does not carry over to the
/// tracer's gap. On the AAL structures of `interslice bench` (separations
/// 0.50–0.74) the walks chosen so lost up to 0.061 to the shape on the
/// skipped slices (caudate-l at k = 6: the box walk held out 0.786
/// against 0.772, on the real slices 0.865 against 0.926); without them
/// `image-guided` went up by 0.46 in total over k = 1..9, its two losses
/// thalamus-r at k = 5 and 6 (−0.008, −0.013), and nothing outside AAL
/// changed. Asking those walks to cut the error below 0.9 / 0.8 / 0.7 of
/// the fusion's instead gained 0.16 / 0.34 / 0.38. A field of pieces keeps
/// its walks: on the T1 k-means classes (separations below 0.75 too) they
/// gain up to 0.11 (class 3), and without them classes 2 and 3 lost
/// 0.07–0.12 at k ≥ 4.
///
/// Why the shape on few slices: one or two held-out slices rank a fit of the image as noisily as
/// they rank the shape candidates, and where the image barely tells the
/// sides apart a fit that clears the bar on them is chance (the same bar
/// keeps the walk off outlines that jump, [`JUMP_WALK_CONTRAST`]). On the AAL
/// structures of `interslice bench` (deep grey structures on a T1,
/// separations 0.51–0.66) the image read on so few slices lost to the
/// shape by up to 0.13 (pallidum-l at k = 6–9: 0.74 / 0.72 / 0.67 / 0.66
/// against 0.83 / 0.83 / 0.81 / 0.79); on the CT and MR lesions (lung2
/// 0.82–0.85, brain1 0.92–0.94) reading it still won by 0.02–0.22.
pub const WEAK_SEPARATION: f64 = 0.75;

/// The narrowest gap, in slices between two drawn ones, across which a walk
/// that covers less than the shape counts as diluted (`walk::undiluted`).
///
/// Why: across a gap of 2 the one skipped slice lies next to a drawn slice
/// on either side, where the walk's probability has not spread out: a walk
/// that covers less than the shape there follows the image, and raising it
/// to the shape's area only undoes that. On the T1 k-means classes at k = 1
/// (`interslice bench`, skipped slices) the box walk raised lost to the
/// walker anchor (class 2 0.8117, class 3 0.7877 against 0.8169 and
/// 0.7919) and, not raised there, is level with it; no other mask changed.
/// From a gap of 4 instead, class 3 at k = 2 lost 0.010 (0.7509 → 0.7411).
pub const DILUTION_MIN_GAP: usize = 3;

/// Whether skipped slice `s` lies between two drawn slices that both show
/// the structure, at least [`DILUTION_MIN_GAP`] apart (inside the traced
/// span, where a walk that covers less than the shape is diluted,
/// `walk::undiluted`), rather than between one that shows it and one that
/// does not, where the structure ends and a walk that shrinks follows it
/// ending.
fn spanned<'a>(
    input: &'a SparseMask<'a>,
) -> Result<impl Fn(usize) -> bool + Sync + 'a, InterpError> {
    let shows = showing(input)?;
    let drawn = input.drawn;
    Ok(move |s| {
        crate::slices::bracket(drawn, s).is_some_and(|g| {
            shows[g] && shows[g + 1] && drawn[g + 1] - drawn[g] >= DILUTION_MIN_GAP
        })
    })
}

/// The largest box, in voxels, the walk of [`Plan::walk`] is tried on: its
/// memory ([`walk::BYTES_PER_VOXEL`] a voxel, 400 MB here) bounds what one
/// interpolation may hold on a server many tracers share. A label whose
/// drawn outlines span more (a whole 512³ cell) keeps the fusion.
pub const MAX_WALK_VOXELS: usize = 1 << 24;

/// An interpolation and, when asked for, its confidence.
type Run = (Mask, Option<Volume<f32>>);

/// The power `γ` of the distance in the prior's scale `τ(δ) = e (δ / r)^γ`
/// ([`Plan::tau`]) where the fusion reads the image raw ([`Reading::Raw`]).
///
/// The fusion's balance of shape and image, `w`, is fitted on held-out
/// slices about twice as far from the kept ones as the real skipped slices
/// are; `τ(δ)` carries it to the real distance. Linearly, the shape near a
/// drawn slice outweighs an image that places the boundary to the pixel
/// (where leave-one-out prefers the raw reading, the image is that sharp)
/// as much as a noisy one. On the development data (`interslice bench`,
/// k = 1–9, 17 masks), with `γ` on a raw reading of 0 / 0.25 / 0.5 / 0.75
/// against 1, the skipped slices' Dice summed over the 153 mask and k
/// pairs rose by 0.084 / 0.162 / 0.202 / 0.163: at 0.5 the MNI grey /
/// white matter means at k = 1 / 3 / 5 / 9 went 0.9701 / 0.9652 / 0.9555 /
/// 0.9408 → 0.9719 / 0.9670 / 0.9578 / 0.9399, T1 class 4 gained up to
/// 0.039 (lost 0.014 at k = 4), the lung lesions 0.001–0.003, and no mask
/// fell below an anchor it was above. On a blurred reading (the noisy
/// phantom, stardist's nuclei) `γ` = 0.5 lost up to 0.016 to the
/// random-walker anchor on stardist's nuclei and 0.005 on the phantom
/// nuclei, so there it stays 1.
pub const RAW_TAU_POWER: f64 = 0.5;

/// The `(w, λ)` grid searched by leave-one-out.
///
/// Why no `w = 8`, though the fit often takes the grid's largest weight:
/// with `(8, 0)` and `(8, 2)` added (`interslice bench`, k = 1–9) the fit
/// took them where the held-out slices favoured them by chance: T1 class 5
/// at k = 1 fell 0.7832 → 0.7084, stardist's nuclei at k = 4 / 5 0.8214 /
/// 0.8001 → 0.8141 / 0.7911, lung2 at k = 6–8 by 0.002–0.004, against
/// gains of at most 0.006 (T1 class 6).
pub const GRID: [(f32, f32); 8] = [
    (0.5, 0.0),
    (1.0, 0.0),
    (2.0, 0.0),
    (4.0, 0.0),
    (0.5, 2.0),
    (1.0, 2.0),
    (2.0, 2.0),
    (4.0, 2.0),
];

/// Scales tried to calibrate the confidence (`σ(c · z)`).
const SCALES: [f32; 6] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0];

/// Scales tried to calibrate the walk's confidence, `σ(c (p − ½))`: its
/// probability `p` is close to 0 or 1 on both sides of a clean edge, also
/// where the tracing puts the boundary a voxel away, so its certainty is
/// learnt from the held-out slices like the fusion's.
pub const WALK_SCALES: [f32; 7] = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];

/// The walk's scale where nothing was held out (two drawn slices): a
/// certain walk (`p` = 0 or 1) counts as 0.88 sure, as sure as a shape
/// blend one pixel from its boundary at the default scale.
pub const UNTESTED_WALK_SCALE: f32 = 4.0;

/// One held-out slice: its truth, the prior's signed distance, the image,
/// and how far (slices) the prediction reached.
type Case<'a> = (Vec<bool>, Vec<f32>, &'a [f32], f64);

/// Image-guided interpolation on one intensity volume.
#[derive(Debug, Clone)]
pub struct ImageGuided {
    image: Conditioned,
    /// Whether this runs on a compact stack of drawn slices
    /// ([`Interpolator::for_stack`]): leave-one-out does not try the random
    /// walk there ([`Plan::walk`]), as the stack holds no image between the
    /// drawn slices for a walker to follow, and the prior does not copy
    /// across jumps ([`fill`]), as `shape-auto` on a stack does not.
    on_stack: bool,
    /// A plan already made ([`ImageGuided::with_plan`]) for the input along
    /// this axis with these drawn slices, used instead of planning again.
    planned: Option<(Axis, Vec<usize>, Plan)>,
    /// Whether a run on a whole volume works on the label's box
    /// ([`ImageGuided::on_the_whole_volume`]).
    boxed: bool,
    /// Whether the fusion may read the image raw ([`Reading`],
    /// [`ImageGuided::blurred_only`]).
    raw_reading: bool,
}

/// Which random walk, if any, a label follows instead of the fusion
/// ([`walk`](mod@walk), Grady 2006, the drawn slices as seeds).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Walk {
    /// No walk: the fusion (or the prior alone).
    Off,
    /// The walk in the band around the shape prior, which seeds the rest:
    /// a thin shell to solve, decided where the fusion would decide.
    Band,
    /// The walk on the label's whole box, seeded by the drawn slices only:
    /// it can follow the image anywhere between them (a thin class that
    /// the prior, interpolated across the gap, misplaces). Its objects are
    /// kept apart as the fusion's are: every pixel it adds belongs to the
    /// prior object nearest along the slice (on a slice past where the
    /// prior ends, the prior's nearest slice that shows the label).
    Box,
}

/// What leave-one-out decided for one label.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Index of the shape prior in [`crate::auto::candidates`].
    pub prior: usize,
    /// Index of the candidate that fills the label where the image is not
    /// read: `shape-auto`'s, which differs from the prior only where it
    /// takes `shape-area` by rule ([`crate::auto::Choice::ranked_first`]).
    pub shape: usize,
    /// The chosen fusion (`w = 0`: shape only).
    pub params: Params,
    /// Pooled held-out Dice of the shape alone and of the chosen fusion.
    pub loo_dice: (f64, f64),
    /// The random walk the label follows instead of the fusion: on the
    /// held-out slices of one leave-one-out run (every other interior drawn
    /// slice) the walk, its objects kept apart, beat the fusion by more than
    /// [`MARGIN`] and, across narrow gaps, cut its error below
    /// [`WALK_RHO`] of it (the box walk measured against what was chosen
    /// without it); the pooled Dice are `walk_dice` (fusion, band walk, box
    /// walk).
    pub walk: Walk,
    /// See `walk` (NaN where a walk was not tried).
    pub walk_dice: (f64, f64, f64),
    /// Scale `c` of the walk's confidence `σ(c |p − ½|)` (`p` its
    /// probability of inside), fitted on the held-out slices as the
    /// fusion's is ([`WALK_SCALES`]); [`UNTESTED_WALK_SCALE`] where nothing
    /// was held out.
    pub walk_scale: f32,
    /// Calibrated scale of the logit for the confidence.
    pub scale: f32,
    /// The prior's boundary error on the held-out slices (physical units)
    /// and their mean distance to the drawn slices (slices): `τ(δ)` is the
    /// first scaled by `δ` over the second.
    pub prior_error: (f32, f64),
    /// The drawn slices are a field of pieces
    /// ([`crate::auto::field_of_pieces`]): the whole-box walk's pixels are
    /// not kept apart per object there (`walk_mask`).
    pub field: bool,
    /// How the fusion reads the image: through the 3 × 3 blur or as it is.
    pub reading: Reading,
    model: Option<IntensityModel>,
}

/// How the fusion reads the image's slices, chosen per label by
/// leave-one-out: the fusion is fitted on the blurred image first, and
/// where no walk was taken it is fitted again on the image as it is and
/// kept if its held-out Dice is the better ([`ImageGuided::plan`]).
///
/// Why both: the blur is a little denoising, and on a noisy image it is
/// what lets the histograms tell the sides apart (read raw everywhere, the
/// noisy phantom's nuclei lost 0.001–0.037, stardist's 0.002–0.004 and
/// brain1 0.013–0.024). On a clean image whose classes are thin it smears
/// the boundary the tracer drew on the voxels as they are: with the choice,
/// the T1 k-means classes 4–6 gained 0.055–0.127 on the skipped slices,
/// lung1 0.006, the MNI template's grey and white matter up to 0.007
/// (`interslice bench`). Why after the walks: they were measured against
/// the blurred fusion, and a raw fusion that beat the box walk on the
/// held-out slices lost to it on the real ones (T1 class 2 at k = 2 and
/// 3: −0.019 and −0.013, below the walker anchor).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// Through the 3 × 3 binomial blur ([`model::blur`]).
    Blurred,
    /// The voxels as they are.
    Raw,
}

impl Plan {
    /// The share of the shape's held-out error the image's floor must stay
    /// below ([`FLOOR_SHARE`], [`SHAPE_FLOOR_SHARE`]).
    fn floor_share(&self) -> f64 {
        if self.field {
            FLOOR_SHARE
        } else {
            SHAPE_FLOOR_SHARE
        }
    }

    /// [`IntensityModel::separation`] of the drawn slices (0.5 where they
    /// gave no intensity model).
    pub fn separation(&self) -> f64 {
        self.model.as_ref().map_or(0.5, IntensityModel::separation)
    }

    /// Whether the fusion reads the image (leave-one-out chose a weight
    /// `w > 0` and the drawn slices gave an intensity model); when not, the
    /// method's result is its shape prior, bit for bit.
    pub fn uses_image(&self) -> bool {
        self.walk != Walk::Off || self.fuses()
    }

    /// Whether the fusion reads the image (see [`Plan::uses_image`]).
    fn fuses(&self) -> bool {
        self.params.w > 0.0 && self.model.is_some()
    }

    /// Fit the fusion on held-out `cases` whose shape-only
    /// predictions are `predicted`: the prior's error that scales `τ`, and
    /// the `(w, λ)` of [`GRID`] with the best pooled Dice, kept only where it
    /// clears [`MARGIN`], [`RHO`] and the floor ([`Plan::floor_share`]),
    /// the shape alone otherwise.
    fn fit_fusion(&mut self, cases: &[Case<'_>], predicted: &[&[bool]], plane: &Plane) {
        let plane = *plane;
        self.params = Params::SHAPE_ONLY;
        // The prior's typical boundary error: the mean distance of its wrong
        // pixels from its boundary; where the prior lost the object (no
        // boundary on the slice), their depth inside the truth, how far
        // the boundary moved past them as the object shrank to nothing.
        let (sum, cnt) = cases
            .iter()
            .map(|(truth, phi, ..)| {
                let lost = phi.first().is_some_and(|&d| d == FAR);
                let depth = lost.then(|| signed_distance(truth, &plane));
                phi.iter()
                    .zip(truth)
                    .enumerate()
                    .filter(|(_, (d, t))| (**d < 0.0) != **t)
                    .fold((0.0f64, 0u64), |a, (i, (d, _))| {
                        let d = depth.as_ref().map_or(*d, |depth| depth[i]);
                        (a.0 + f64::from(d.abs()), a.1 + 1)
                    })
            })
            .fold((0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        let px = plane.spacing[0].min(plane.spacing[1]);
        let mean_reach = cases.iter().map(|c| c.3).sum::<f64>() / cases.len() as f64;
        self.prior_error = (((sum / cnt.max(1) as f64).max(0.5 * px)) as f32, mean_reach);
        let plan_tau = self.clone();
        let score = |p: Params, model: &IntensityModel| -> f64 {
            let acc = cases
                .par_iter()
                .map(|(truth, phi, img, delta)| {
                    let t = (plan_tau.tau(*delta), *delta);
                    overlap(&fuse(phi, img, model, &plane, t, p).0, truth)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            pooled_dice(acc)
        };
        let base = {
            let acc = cases
                .iter()
                .zip(predicted)
                .map(|((truth, ..), p)| overlap(p, truth))
                .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            pooled_dice(acc)
        };
        self.loo_dice = (base, base);
        if let Some(model) = &self.model {
            let mut best = (Params::SHAPE_ONLY, f64::NEG_INFINITY);
            for (w, lambda) in GRID {
                let p = Params { w, lambda };
                let d = score(p, model);
                if d > best.1 {
                    best = (p, d);
                }
            }
            // The image's floor: what the fusion gets wrong where the
            // prior is already right (see `Plan::floor_share`).
            let floor = if best.0.w > 0.0 {
                let p = best.0;
                let acc = cases
                    .par_iter()
                    .map(|(truth, _, img, delta)| {
                        let d = (delta / 2.0).max(1.0);
                        let t = (plan_tau.tau(d), d);
                        let phi = prior_distance(truth, &plane);
                        overlap(&fuse(&phi, img, model, &plane, t, p).0, truth)
                    })
                    .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
                1.0 - pooled_dice(acc)
            } else {
                0.0
            };
            let shape_error = 1.0 - base;
            if best.1 > base + MARGIN
                && 1.0 - best.1 < RHO * shape_error
                && floor < self.floor_share() * shape_error
            {
                self.params = best.0;
            }
            self.loo_dice.1 = best.1;
        }
    }

    /// This plan (fitted on the blurred image) with the fusion refitted on
    /// the image read as it is ([`Reading::Raw`]: the held-out `cases` of
    /// that reading and its intensity `model`), calibrated, where that
    /// fusion is used and its held-out Dice beats this plan's best fit
    /// (the blurred fusion's, used or vetoed by its floor); `None`
    /// otherwise.
    fn read_raw(
        &self,
        model: Option<IntensityModel>,
        cases: &[Case<'_>],
        predicted: &[&[bool]],
        plane: &Plane,
    ) -> Option<Plan> {
        let mut raw = Plan {
            model,
            reading: Reading::Raw,
            ..self.clone()
        };
        raw.fit_fusion(cases, predicted, plane);
        // Against the blurred reading's best fit even where the floor
        // vetoed it: a raw reading that fits the held-out slices worse is
        // no way round that veto. On the noisy phantom's cell at k = 7
        // (`image::on_the_noisy_phantom_...`) the blurred fusion (held out
        // 0.9728, floor 0.48 of the shape's error) was vetoed and the raw
        // one (0.9633, just under `RHO`) was taken: 0.9903 → 0.9842 on the
        // skipped slices. No pair of `interslice bench` changed.
        let better = raw.fuses() && raw.loo_dice.1 > self.loo_dice.1;
        better.then(|| {
            raw.calibrate(cases, plane);
            raw
        })
    }

    /// Calibrate the confidence of the fitted fusion on held-out `cases`:
    /// the scale of the logit with the least log-loss (a one-parameter
    /// Platt scaling).
    fn calibrate(&mut self, cases: &[Case<'_>], plane: &Plane) {
        let plane = *plane;
        let flat = IntensityModel::flat();
        let m = self.model.as_ref().unwrap_or(&flat);
        let logits: Vec<(Vec<f32>, &Vec<bool>)> = cases
            .par_iter()
            .map(|(truth, phi, img, delta)| {
                let t = (self.tau(*delta), *delta);
                (fuse(phi, img, m, &plane, t, self.params).1, truth)
            })
            .collect();
        self.scale = best_scale(&SCALES, logits.iter().map(|(z, t)| (z, *t)));
    }

    /// The prior's scale `τ` at `delta` slices from the nearest drawn slice:
    /// the held-out boundary error `e`, measured at the held-out slices'
    /// mean distance `r` from the kept ones, carried to `delta` as
    /// `e (δ / r)^γ`: linearly (`γ = 1`) where the fusion reads the image
    /// blurred, as [`RAW_TAU_POWER`] where it reads it raw.
    pub fn tau(&self, delta: f64) -> f32 {
        let (e, reach) = self.prior_error;
        let power = match self.reading {
            Reading::Blurred => 1.0,
            Reading::Raw => RAW_TAU_POWER,
        };
        (e * (delta / reach.max(1.0)).powf(power) as f32).max(1e-6)
    }
}

impl ImageGuided {
    /// The method on `image`; it must lie on the grid of the masks it is given
    /// (checked by [`Interpolator::interpolate`]). It reads `image`
    /// [`Conditioned`]: finite, at a workable scale (a plain image is
    /// conditioned here; a server cell's shared intensities are not scanned
    /// again).
    pub fn new(image: impl Into<Conditioned>) -> ImageGuided {
        ImageGuided {
            image: image.into(),
            on_stack: false,
            planned: None,
            boxed: true,
            raw_reading: true,
        }
    }

    /// The method whose fusion always reads the image through the blur
    /// (what the choice of [`Reading`] is measured against).
    pub fn blurred_only(self) -> ImageGuided {
        ImageGuided {
            raw_reading: false,
            ..self
        }
    }

    /// The method that never works on a label's box when given a whole
    /// volume: its plan, result and confidence are computed on every voxel
    /// (what the box is tested against).
    pub fn on_the_whole_volume(self) -> ImageGuided {
        ImageGuided {
            boxed: false,
            ..self
        }
    }

    /// The method with `plan` made by [`ImageGuided::plan`] for `input`: an
    /// interpolation of an input along the same axis with the same drawn
    /// slices uses it instead of running leave-one-out again (a caller that
    /// asked for the plan first, to say whether the image helps, pays once).
    pub fn with_plan(mut self, input: &SparseMask<'_>, plan: Plan) -> ImageGuided {
        self.planned = Some((input.axis, input.drawn.to_vec(), plan));
        self
    }

    fn image_slice(
        &self,
        vol: &Volume<f32>,
        input: &SparseMask<'_>,
        s: usize,
        reading: Reading,
    ) -> Vec<f32> {
        let plane = Plane::of(input);
        let raw = vol.slice(input.axis, s).expect("slice in range");
        match reading {
            Reading::Blurred => blur(&raw, plane.width, plane.height),
            Reading::Raw => raw,
        }
    }

    /// [`model::edge_contrast`] of the drawn slices on the image as it is,
    /// unblurred, as the walk's edge weights read it (0 where it cannot be
    /// measured). `drawn_pairs` holds each drawn slice's mask.
    fn edge_contrast(&self, input: &SparseMask<'_>, drawn_pairs: &[(Vec<bool>, Vec<f32>)]) -> f64 {
        // Only the drawn slices that show the label are read: the rest
        // hold no boundary.
        let raw: Vec<Option<Vec<f32>>> = input
            .drawn
            .par_iter()
            .zip(drawn_pairs)
            .map(|(&d, (m, _))| {
                m.iter().any(|&x| x).then(|| {
                    self.image
                        .slice(input.axis, d)
                        .expect("validated drawn index")
                })
            })
            .collect();
        let slices = drawn_pairs
            .iter()
            .zip(&raw)
            .filter_map(|((m, _), i)| Some((m.as_slice(), i.as_deref()?)));
        model::edge_contrast(slices, &Plane::of(input)).unwrap_or(0.0)
    }

    /// Decide, on the drawn slices of `input`, the prior and the fusion:
    /// on the label's box and the box's part of the image
    /// ([`BoxReach::Image`]) where it is smaller than the volume, which
    /// gives the whole volume's plan (property-tested against
    /// [`ImageGuided::on_the_whole_volume`]), so a caller that asks for the
    /// plan of a whole cell (the server's recommendation) pays for the
    /// label's surroundings only.
    pub fn plan(&self, input: &SparseMask<'_>) -> Result<Plan, InterpError> {
        input.validate()?;
        check_grid(&self.image, input)?;
        if input.in_box || self.on_stack || !self.boxed {
            return self.plan_here(input);
        }
        let (axis, geometry) = (input.axis, input.mask.geometry());
        let planes = drawn_planes(input)?;
        let slices = DrawnSlice::of(input, &planes);
        for b in LabelBox::tries(geometry, axis, &slices, BoxReach::Image) {
            let (m, drawn) = b.sparse(geometry, axis, &slices)?;
            let mut boxed = SparseMask::new(&m, axis, &drawn).inside_box();
            boxed.cancel = input.cancel;
            match self.on(&b).plan_here(&boxed) {
                Err(InterpError::OutsideBox) => continue,
                plan => return plan,
            }
        }
        self.plan_here(input)
    }

    /// The method on the part `b` of the volume: its image cut to the box,
    /// a plan made on the whole volume carried over (what it reads lies
    /// inside), its drawn slices counted from the box's first.
    fn on(&self, b: &LabelBox) -> ImageGuided {
        let planned = self.planned.as_ref().map(|(axis, drawn, plan)| {
            let (lo, n) = (b.lo[axis.dim()], b.dims[axis.dim()]);
            let inside = drawn
                .iter()
                .filter(|&&d| (lo..lo + n).contains(&d))
                .map(|&d| d - lo)
                .collect();
            (*axis, inside, plan.clone())
        });
        ImageGuided {
            image: self.image.cut(b),
            on_stack: self.on_stack,
            planned,
            boxed: self.boxed,
            raw_reading: self.raw_reading,
        }
    }

    /// The result and its confidence computed on the label's box grown
    /// until the confidence reaches [`crate::crop::SURE`] at its sides, 1
    /// taken outside, as the label runner takes a shape method's
    /// ([`LabelBox::grown_for_confidence`]). How far that is depends on the
    /// plan, so the plan comes first (on the box, [`ImageGuided::plan`]):
    /// past the fusion's band and the walk's box every confidence this
    /// method writes is `σ(c |φ| / τ)` or surer, `c` the plan's scale and
    /// `τ` the larger of the shape's `τ(δ)` and the plan's, `δ` at most the
    /// widest gap less one. `None` (the whole volume, then) where the grown
    /// box is the whole volume, the run reaches past it, or the method
    /// runs on the whole volume anyway.
    fn confidence_on_box(
        &self,
        input: &SparseMask<'_>,
    ) -> Result<Option<(Mask, Volume<f32>)>, InterpError> {
        if input.in_box || self.on_stack || !self.boxed {
            return Ok(None);
        }
        input.validate()?;
        check_grid(&self.image, input)?;
        let plan = match &self.planned {
            Some((axis, drawn, plan)) if *axis == input.axis && drawn == input.drawn => {
                plan.clone()
            }
            _ => self.plan(input)?,
        };
        let (axis, geometry) = (input.axis, input.mask.geometry());
        let plane = Plane::of(input);
        let widest = input.drawn.windows(2).map(|w| w[1] - w[0]).max();
        let delta = widest.unwrap_or(1).saturating_sub(1) as f64;
        let tau_max = tau(&plane, delta).max(plan.tau(delta));
        let reach = f64::from(tau_max / plan.scale);
        let planes = drawn_planes(input)?;
        let slices = DrawnSlice::of(input, &planes);
        let planned = self.clone().with_plan(input, plan);
        for b in LabelBox::tries(geometry, axis, &slices, BoxReach::Image) {
            let Some(grown) = b.grown_until_sure(geometry, axis, reach) else {
                return Ok(None);
            };
            let run = grown.interpolate(&planned, (geometry, axis), &slices, true, input.cancel)?;
            if let Some(on_box) = run {
                let (mask, conf) = grown.onto_volume(geometry, on_box);
                return Ok(Some((mask, conf.expect("confidence requested"))));
            }
        }
        Ok(None)
    }

    /// [`ImageGuided::plan`] on `input` as it is.
    fn plan_here(&self, input: &SparseMask<'_>) -> Result<Plan, InterpError> {
        input.validate()?;
        check_grid(&self.image, input)?;
        let plane = Plane::of(input);
        let (shape, choice) = ShapeAuto::default().choose(input)?.ranked_first();
        let prior = choice.index;
        // Each drawn slice's mask with its image slice blurred, and as it
        // is (see `Reading`).
        let read = |reading| -> Vec<(Vec<bool>, Vec<f32>)> {
            input
                .drawn
                .par_iter()
                .map(|&d| {
                    let m = input
                        .mask
                        .slice(input.axis, d)
                        .expect("validated drawn index");
                    (m, self.image_slice(&self.image, input, d, reading))
                })
                .collect()
        };
        let (drawn_pairs, raw_pairs) = (read(Reading::Blurred), read(Reading::Raw));
        let learn = |pairs: &[(Vec<bool>, Vec<f32>)]| {
            IntensityModel::learn(
                pairs.iter().map(|(m, i)| (m.as_slice(), i.as_slice())),
                &plane,
            )
        };
        let (model, raw_model) = (learn(&drawn_pairs), learn(&raw_pairs));
        let mut plan = Plan {
            prior,
            shape,
            params: Params::SHAPE_ONLY,
            loo_dice: (f64::NAN, f64::NAN),
            walk: Walk::Off,
            walk_dice: (f64::NAN, f64::NAN, f64::NAN),
            walk_scale: UNTESTED_WALK_SCALE,
            scale: 1.0,
            prior_error: (plane.spacing[0].min(plane.spacing[1]) as f32, 1.0),
            field: drawn_field(&choice.compact),
            reading: Reading::Blurred,
            model,
        };
        if choice.thin {
            // `shape-auto` took the shape by rule, too little held out to rank
            // it (`auto::FEW_HELD_OUT`), and what is held out would rank the
            // image no better (see `THIN_SHAPE_GAP`).
            if median_gap(&choice.compact.real).is_none_or(|g| g <= THIN_SHAPE_GAP) {
                return Ok(plan);
            }
            if !self.on_stack && self.edge_contrast(input, &drawn_pairs) >= EDGE_CONTRAST {
                plan.walk = Walk::Box;
            }
            return Ok(plan);
        }
        if choice.few && plan.separation() < WEAK_SEPARATION {
            // See `WEAK_SEPARATION`.
            return Ok(plan);
        }
        let (compact, held) = (&choice.compact, &choice.held);
        if held
            .iter()
            .all(|h| !compact.truth(h.pos).iter().any(|&x| x))
        {
            // Nothing held out that shows the label. Where two neighbouring
            // drawn slices show it, each predicts the other (`cross_cases`)
            // and the fusion is fitted on that; where it finds no use for
            // the image, the whole-box walk may follow a clear edge (see
            // `EDGE_SEPARATION` and `BLIND_WALK_GAP`).
            let sep = plan.separation();
            let wide = alone_across(input.drawn, &showing(input)?, BLIND_WALK_GAP);
            let trusted = sep >= EDGE_SEPARATION || wide;
            if sep >= EDGE_SEPARATION {
                let (cases, copies) = cross_cases(input, &drawn_pairs, &plane);
                if !cases.is_empty() {
                    plan.fit_fusion(&cases, &copies, &plane);
                    plan.calibrate(&cases, &plane);
                    let (raw_cases, _) = cross_cases(input, &raw_pairs, &plane);
                    if self.raw_reading
                        && let Some(raw) = plan.read_raw(raw_model, &raw_cases, &copies, &plane)
                    {
                        plan = raw;
                    }
                }
            }
            if !plan.fuses() && !self.on_stack && trusted && !pole_fill(prior, input)? {
                plan.walk = Walk::Box;
            }
            return Ok(plan);
        }
        // Per held-out slice: its truth, the prior's signed distance, the
        // image, and how far the prediction reached. The compact stack holds
        // the drawn slices near the label only, so its positions are looked
        // up among all drawn slices.
        let index_of = |pos: usize| {
            input
                .drawn
                .binary_search(&compact.real[pos])
                .expect("a compact slice is a drawn slice")
        };
        let cases: Vec<Case<'_>> = held
            .par_iter()
            .map(|h| {
                (
                    compact.truth(h.pos),
                    prior_distance(&h.predicted, &plane),
                    drawn_pairs[index_of(h.pos)].1.as_slice(),
                    compact.reach(h.pos) as f64,
                )
            })
            .collect();
        let predicted: Vec<&[bool]> = held.iter().map(|h| h.predicted.as_slice()).collect();
        plan.fit_fusion(&cases, &predicted, &plane);
        plan.calibrate(&cases, &plane);
        if !self.on_stack {
            self.try_walk(input, &choice, &cases, &mut plan)?;
            if plan.walk == Walk::Off
                && !plan.fuses()
                && !jumping_gaps(input)?.is_empty()
                && plan.separation() >= WEAK_SEPARATION
                && self.edge_contrast(input, &drawn_pairs) >= JUMP_WALK_CONTRAST
            {
                // See `JUMP_WALK_CONTRAST`.
                plan.walk = Walk::Box;
            }
        }
        // The image as it is, where no walk was taken: the walks were
        // measured against the blurred reading's fusion (see `Reading`).
        if plan.walk == Walk::Off && self.raw_reading {
            let raw_cases: Vec<Case<'_>> = held
                .iter()
                .zip(&cases)
                .map(|(h, (truth, phi, _, reach))| {
                    let img = raw_pairs[index_of(h.pos)].1.as_slice();
                    (truth.clone(), phi.clone(), img, *reach)
                })
                .collect();
            if let Some(raw) = plan.read_raw(raw_model, &raw_cases, &predicted, &plane) {
                plan = raw;
            }
        }
        Ok(plan)
    }

    /// Whether the random walk predicts the held-out slices of one
    /// leave-one-out run better than the plan's fusion (or prior): the
    /// walk runs on the volume with those drawn slices erased, and each
    /// held-out slice's walk is kept in the band of the prior's prediction
    /// with its objects apart, as the fusion is.
    fn try_walk(
        &self,
        input: &SparseMask<'_>,
        choice: &Choice,
        cases: &[Case<'_>],
        plan: &mut Plan,
    ) -> Result<(), InterpError> {
        if !plan.field && plan.separation() < WEAK_SEPARATION {
            // See `WEAK_SEPARATION`.
            return Ok(());
        }
        let plane = Plane::of(input);
        let compact = &choice.compact;
        // The held-out slices of the run that keeps the even positions.
        let odd: Vec<usize> = (0..choice.held.len())
            .filter(|&i| choice.held[i].pos % 2 == 1)
            .collect();
        if odd.is_empty() {
            return Ok(());
        }
        let erased: Vec<usize> = odd
            .iter()
            .map(|&i| compact.real[choice.held[i].pos])
            .collect();
        let kept: Vec<usize> = input
            .drawn
            .iter()
            .copied()
            .filter(|d| !erased.contains(d))
            .collect();
        let mut sparse = input.mask.clone();
        let empty = vec![false; plane.width * plane.height];
        for &e in &erased {
            sparse.set_slice(input.axis, e, &empty)?;
        }
        let mut held_input = SparseMask::new(&sparse, input.axis, &kept);
        held_input.cancel = input.cancel;
        held_input.in_box = input.in_box;
        let prior = fill(plan.prior, held_input, None)?;
        let flat = IntensityModel::flat();
        let model = plan.model.as_ref().unwrap_or(&flat);
        // The fusion the walk must beat, fitted without the slices it is
        // scored on (see `REFIT_MIN_CASES`).
        let even: Vec<usize> = (0..choice.held.len())
            .filter(|&i| choice.held[i].pos.is_multiple_of(2))
            .collect();
        let mut rival = plan.clone();
        if plan.fuses() && even.len() >= REFIT_MIN_CASES {
            let even_cases: Vec<Case<'_>> = even.iter().map(|&i| cases[i].clone()).collect();
            let even_predicted: Vec<&[bool]> = even
                .iter()
                .map(|&i| choice.held[i].predicted.as_slice())
                .collect();
            rival.fit_fusion(&even_cases, &even_predicted, &plane);
        }
        let ours: Vec<Vec<bool>> = odd
            .par_iter()
            .map(|&i| {
                let (_, phi, img, delta) = &cases[i];
                if rival.fuses() {
                    let t = (rival.tau(*delta), *delta);
                    fuse(phi, img, model, &plane, t, rival.params).0
                } else {
                    choice.held[i].predicted.clone()
                }
            })
            .collect();
        let held_dice = |masks: &[Vec<bool>]| {
            let acc = masks
                .par_iter()
                .zip(&odd)
                .map(|(m, &i)| overlap(m, &cases[i].0))
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            pooled_dice(acc)
        };
        // The walk's decision on each held-out slice, kept apart per object
        // within `reach(δ)` of the prior's boundary: its pooled Dice, and its
        // logits to fit the scale of its confidence on should it be chosen.
        let field = plan.field;
        let decided = |walked: &walk::Walked, reach: &(dyn Fn(f64) -> f32 + Sync)| {
            let (masks, logits): (Vec<Vec<bool>>, Vec<Vec<f32>>) = odd
                .par_iter()
                .zip(&erased)
                .map(|(&i, &real)| {
                    let (_, phi, _, delta) = &cases[i];
                    let z = walked
                        .logit(real, &plane)
                        .unwrap_or_else(|| vec![-0.5; plane.len()]);
                    let z = walk::undiluted(z, phi);
                    (walk_mask(field, phi, &z, &plane, reach(*delta)), z)
                })
                .unzip();
            (held_dice(&masks), logits)
        };
        // On the walk's box and a ring around it (`Walked::fit_region`).
        let fit_scale = |walked: &walk::Walked, logits: &[Vec<f32>]| {
            let region = walked.fit_region(&plane);
            let within = |z: &[f32], truth: &[bool]| -> (Vec<f32>, Vec<bool>) {
                z.iter()
                    .zip(truth)
                    .zip(&region)
                    .filter(|&(_, &r)| r)
                    .map(|((&z, &t), _)| (z, t))
                    .unzip()
            };
            let pairs: Vec<(Vec<f32>, Vec<bool>)> = logits
                .iter()
                .zip(&odd)
                .map(|(z, &i)| within(z, &cases[i].0))
                .collect();
            best_scale(&WALK_SCALES, pairs.iter().map(|(z, t)| (z, t)))
        };
        let fused = held_dice(&ours);
        let in_band = |delta: f64| band(&plane, delta);
        let seeds = |s: usize| band_seeds(&prior, &held_input, s);
        let Some(walked) = self.walker().walk_with(&held_input, Some(&seeds))? else {
            return Ok(());
        };
        let (banded, band_logits) = decided(&walked, &in_band);
        plan.walk_dice = (fused, banded, f64::NAN);
        let widest = compact.real.windows(2).map(|w| w[1] - w[0]).max();
        let wide = widest >= Some(BOX_WALK_MIN_GAP) || field;
        let rho = if wide { 1.0 } else { WALK_RHO };
        let clears = |walk: f64, than: f64| walk > than + MARGIN && 1.0 - walk < rho * (1.0 - than);
        if clears(banded, fused) {
            plan.walk = Walk::Band;
            plan.walk_scale = fit_scale(&walked, &band_logits);
        }
        if !wide || 1.0 - banded > BOX_WALK_GATE * (1.0 - fused) {
            return Ok(());
        }
        let Some(walked) = self.walker().walk_with(&held_input, None)? else {
            return Ok(());
        };
        let (boxed, box_logits) = decided(&walked, &|_| f32::INFINITY);
        plan.walk_dice.2 = boxed;
        let chosen = if plan.walk == Walk::Band {
            banded
        } else {
            fused
        };
        if clears(boxed, chosen) {
            plan.walk = Walk::Box;
            plan.walk_scale = fit_scale(&walked, &box_logits);
        }
        Ok(())
    }

    /// Interpolate with a plan; the confidence too when `confidence` is set.
    fn run(&self, input: &SparseMask<'_>, confidence: bool) -> Result<Run, InterpError> {
        let plan = match &self.planned {
            Some((axis, drawn, plan)) if *axis == input.axis && drawn == input.drawn => {
                plan.clone()
            }
            _ => self.plan(input)?,
        };
        input.check_cancelled()?;
        // The prior the image reads fades the jumps on the straight line
        // (both outlines' cores on every skipped slice, for the image to
        // pick); where the shape alone is the result it is `shape-auto`'s,
        // eased ([`Fade`]).
        let model = plan.model.as_ref().filter(|_| plan.fuses());
        let reads_image = plan.walk != Walk::Off || model.is_some();
        let fade = |profile| (!self.on_stack).then_some(profile);
        let eased = fade(Fade::Eased);
        let prior_fade = if reads_image {
            fade(Fade::Linear)
        } else {
            eased
        };
        let index = if reads_image { plan.prior } else { plan.shape };
        let prior = fill(index, *input, prior_fade)?;
        if plan.walk != Walk::Off
            && let Some(walked) = self.run_walk(input, &prior, &plan, confidence)?
        {
            return Ok(walked);
        }
        let Some(model) = model else {
            let shape = if !reads_image {
                prior
            } else {
                // The walk declined the box: the shape alone after all.
                fill(plan.shape, *input, eased)?
            };
            let c = confidence.then(|| shape_confidence(&shape, input, plan.scale));
            return Ok((shape, c));
        };
        let plane = Plane::of(input);
        decide_slices(
            input,
            &prior,
            ((confidence, plan.scale), false),
            |s, delta, phi, _own| {
                let img = self.image_slice(&self.image, input, s, plan.reading);
                let t = (plan.tau(delta), delta);
                Some(fuse(phi, &img, model, &plane, t, plan.params))
            },
            |z| sigmoid(plan.scale * z.abs()),
        )
    }
}

/// The walk's decision `z > 0` on one skipped slice (prior `phi`) of a
/// tracing that is a `field` of pieces or not ([`Plan::field`]), its
/// pixels given to the prior's objects within `reach` of them and kept
/// apart ([`separate`]) — except on the whole box (`reach` infinite) of
/// a field of pieces, where it is `z > 0` as it stands.
///
/// Why: the pieces of a field (a tissue class of many pieces per slice)
/// join and split from one drawn slice to the next, so the tracing does
/// not say they are apart; dropping every walk pixel that touches
/// another piece cut the walk's joins where the class does join. On the
/// T1 k-means classes (`interslice bench`, skipped slices) the box walk
/// without it gained 0.009–0.013 on class 2 and 0.008–0.018 on class 3
/// at every k where it is taken, and reached or passed the walker anchor
/// on classes 1–3 at k = 1, 3, 5 and 9. Objects that are not a field (two
/// balls the image bridges) stay apart as before.
fn walk_mask(field: bool, phi: &[f32], z: &[f32], plane: &Plane, reach: f32) -> Vec<bool> {
    if field && reach == f32::INFINITY {
        z.iter().map(|&v| v > 0.0).collect()
    } else {
        separate(phi, z, plane, reach)
    }
}

/// Each skipped slice between drawn ones where the `prior` shows the label,
/// decided by `decide(s, δ, φ, own)` (`δ` the distance to the nearest drawn
/// slice, `φ` the prior's signed distance, `own` whether that is `s`'s own
/// prior rather than a neighbour's) into its mask and a logit, `None`
/// to keep the prior empty there; the volume assembled and, when
/// `confidence.0`, the confidence: `confidence_of(logit)` on those slices,
/// the shape's (at scale `confidence.1`) elsewhere.
///
/// With `beyond_prior`, a skipped slice where the prior is empty is decided
/// too, `φ` that of the nearest slice where the prior shows the label (what
/// keeps the decision's objects apart there): the whole-box walk follows
/// the image past where the shape ends (see [`Walk::Box`]).
fn decide_slices(
    input: &SparseMask<'_>,
    prior: &Mask,
    (confidence, beyond_prior): ((bool, f32), bool),
    decide: impl Fn(usize, f64, &[f32], bool) -> Option<(Vec<bool>, Vec<f32>)> + Sync,
    confidence_of: impl Fn(f32) -> f32,
) -> Result<Run, InterpError> {
    let plane = Plane::of(input);
    let drawn = input.drawn;
    let n = input.mask.slice_count(input.axis);
    let shows: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|s| shows_on(prior, input.axis, s).expect("slice in range"))
        .collect();
    let (first, last) = (drawn[0], drawn[drawn.len() - 1]);
    // The slice whose prior stands in for `s`'s: its own, or where it is
    // empty and `beyond_prior`, the nearest within the drawn range that
    // shows the label (the lower one on a tie).
    let reference = |s: usize| -> Option<usize> {
        if shows[s] {
            return Some(s);
        }
        if !beyond_prior {
            return None;
        }
        (1..=last - first).find_map(|d| {
            [s.checked_sub(d), Some(s + d)]
                .into_iter()
                .flatten()
                .find(|&t| (first..=last).contains(&t) && shows[t])
        })
    };
    let decided: Vec<Option<(Vec<bool>, Vec<f32>)>> = (0..n)
        .into_par_iter()
        .map(|s| {
            if input.is_cancelled() {
                return None;
            }
            let delta = to_nearest_drawn(drawn, s)?;
            let p = prior
                .slice(input.axis, reference(s)?)
                .expect("slice in range");
            decide(s, delta, &signed_distance(&p, &plane), shows[s])
        })
        .collect();
    let mask = assemble(input, |s| decided[s].as_ref().map(|f| f.0.clone()))?;
    let conf = confidence.0.then(|| {
        let mut c = shape_confidence(&mask, input, confidence.1);
        for (s, f) in decided.iter().enumerate() {
            if let Some((_, z)) = f {
                // NaN: the decision says nothing there (past the walk's
                // box), and the shape's confidence stands.
                let shape = c.slice(input.axis, s).expect("slice in range");
                let v: Vec<f32> = z
                    .iter()
                    .zip(shape)
                    .map(|(&x, sc)| if x.is_nan() { sc } else { confidence_of(x) })
                    .collect();
                c.set_slice(input.axis, s, &v).expect("slice in range");
            }
        }
        c
    });
    Ok((mask, conf))
}

impl ImageGuided {
    /// The walk of [`Plan::walk`], bounded by [`MAX_WALK_VOXELS`].
    fn walker(&self) -> RandomWalk {
        RandomWalk::within(self.image.clone(), MAX_WALK_VOXELS)
    }

    /// The random walk of [`Plan::walk`] on `input` (in the band of `prior`
    /// or on the whole box), its objects kept apart on every skipped slice;
    /// the confidence is `σ(c (p − ½))` of the walk's probability, at the
    /// plan's [`Plan::walk_scale`]. `None`
    /// when the walk declines the box (larger than on the leave-one-out run).
    fn run_walk(
        &self,
        input: &SparseMask<'_>,
        prior: &Mask,
        plan: &Plan,
        confidence: bool,
    ) -> Result<Option<Run>, InterpError> {
        let plane = Plane::of(input);
        let seeds = |s: usize| band_seeds(prior, input, s);
        let boxed = plan.walk == Walk::Box;
        let spans = spanned(input)?;
        let seeded: Option<&walk::Seeds<'_>> = (!boxed).then_some(&seeds);
        let Some(walked) = self.walker().walk_with(input, seeded)? else {
            return Ok(None);
        };
        decide_slices(
            input,
            prior,
            ((confidence, plan.scale), boxed),
            |s, delta, phi, own| {
                let z = walked.logit(s, &plane)?;
                // Raised to the prior's area only where the prior shows the
                // label on this slice (not where `phi` is a neighbour's).
                let z = if spans(s) && own {
                    walk::undiluted(z, phi)
                } else {
                    z
                };
                let reach = if boxed {
                    f32::INFINITY
                } else {
                    band(&plane, delta)
                };
                let mask = walk_mask(plan.field, phi, &z, &plane, reach);
                Some((mask, walked.in_box_only(z, s, &plane)))
            },
            |z| sigmoid(plan.walk_scale * z.abs()),
        )
        .map(Some)
    }
}

impl Interpolator for ImageGuided {
    fn name(&self) -> &'static str {
        "image-guided"
    }

    fn description(&self) -> &'static str {
        "shape prior fused with the intensity likelihood of the drawn slices, weight chosen by leave-one-out (needs --image)"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        // Every slice: its walk reads the prior on the slices between the
        // ones a caller reads (`SparseMask::only`).
        Ok(self.run(&input.every_slice(), false)?.0)
    }

    fn box_reach(&self) -> BoxReach {
        BoxReach::Image
    }

    fn for_box(&self, b: &LabelBox) -> Option<Box<dyn Interpolator>> {
        Some(Box::new(self.on(b)))
    }

    fn interpolate_with_confidence(
        &self,
        input: SparseMask<'_>,
    ) -> Result<(Mask, Volume<f32>), InterpError> {
        let input = input.every_slice();
        if let Some(on_box) = self.confidence_on_box(&input)? {
            return Ok(on_box);
        }
        let (m, c) = self.run(&input, true)?;
        Ok((m, c.expect("confidence requested")))
    }

    fn for_stack(
        &self,
        axis: Axis,
        real: &[usize],
    ) -> Result<Option<Box<dyn Interpolator>>, InterpError> {
        let stacked = crate::loo::stack(&self.image, axis, real)?;
        Ok(Some(Box::new(ImageGuided {
            on_stack: true,
            boxed: self.boxed,
            ..ImageGuided::new(Arc::new(stacked))
        })))
    }
}

/// Held-out cases for a label of which nothing between the drawn slices
/// can be held out (two drawn slices show it, as on a lesion seen on three
/// slices and traced on the first and last): each drawn slice that shows
/// the label predicted by copying the outline of a drawn neighbour that
/// shows it too, its image the drawn slice's own. The copies are returned
/// beside the cases, as the shape's predictions to beat.
///
/// Why a copy and not the prior: the prior of two drawn slices lies
/// between them, where nothing is traced. A copy errs by the whole change
/// from one drawn outline to the next, about twice what the prior errs in
/// the middle of the gap, as leave-one-out's held-out slices err across
/// twice the tracer's gap; the fusion is then kept by the same bars
/// ([`MARGIN`], [`RHO`], the floor). On the development data (`interslice
/// bench`, skipped slices) the CT lung lesion lung1 and the MR breast
/// lesion, each traced on its first and last of three slices, went from
/// the shape's profile 0.847 and 0.814 to 0.944 and 0.871 (the boxed
/// walker anchor 0.902 and 0.656), and brain1 at k ≥ 5, a lesion whose
/// two drawn outlines do not overlap (each copy scores 0, the fusion
/// 0.41), from the walk's 0.509 to 0.718 (shape 0.436, anchor 0.488).
fn cross_cases<'a>(
    input: &SparseMask<'_>,
    drawn_pairs: &'a [(Vec<bool>, Vec<f32>)],
    plane: &Plane,
) -> (Vec<Case<'a>>, Vec<&'a [bool]>) {
    let shows: Vec<bool> = drawn_pairs
        .iter()
        .map(|(m, _)| m.iter().any(|&x| x))
        .collect();
    let pairs: Vec<(usize, usize)> = (0..shows.len())
        .flat_map(|i| [(i, i.wrapping_sub(1)), (i, i + 1)])
        .filter(|&(i, j)| j < shows.len() && shows[i] && shows[j])
        .collect();
    pairs
        .par_iter()
        .map(|&(i, j)| {
            let (truth, image) = &drawn_pairs[i];
            let copy = drawn_pairs[j].0.as_slice();
            let case = (
                truth.clone(),
                signed_distance(copy, plane),
                image.as_slice(),
                input.drawn[i].abs_diff(input.drawn[j]) as f64,
            );
            (case, copy)
        })
        .unzip()
}

/// The signed distance of a prior's slice `mask` (negative inside), or
/// "no object near" ([`FAR`]) everywhere where it is empty: not the
/// slice's diagonal, as [`signed_distance`] gives, so that a label's box
/// ([`crate::crop`]) fits and fuses as the whole volume does. A held-out
/// slice the prior lost counted the slice's size in the prior's error
/// ([`Plan::tau`]): the same tracing was fitted with `τ` 24.9 µm on an
/// 80 × 72 slice and 11.5 µm on its 35 × 31 box.
fn prior_distance(mask: &[bool], plane: &Plane) -> Vec<f32> {
    if mask.iter().any(|&x| x) {
        signed_distance(mask, plane)
    } else {
        vec![FAR; mask.len()]
    }
}

/// Seeds for the walk of [`Plan::walk`] on skipped slice `s` of `input`
/// (`None` for a drawn slice or one outside the drawn range): the `prior`
/// (1 inside, 0 outside) farther than the fusion's band ([`band`]) from its
/// boundary, NaN (the walk decides) in the band; a slice where the prior is
/// empty is all outside. What the walk could decide past the band,
/// [`separate`] would drop anyway.
fn band_seeds(prior: &Mask, input: &SparseMask<'_>, s: usize) -> Option<Vec<f32>> {
    let plane = Plane::of(input);
    let delta = to_nearest_drawn(input.drawn, s)?;
    let p = prior.slice(input.axis, s).ok()?;
    if !p.iter().any(|&x| x) {
        return Some(vec![0.0; plane.len()]);
    }
    let b = band(&plane, delta);
    let phi = signed_distance(&p, &plane);
    Some(
        phi.iter()
            .map(|&d| {
                if d.abs() <= b {
                    f32::NAN
                } else if d < 0.0 {
                    1.0
                } else {
                    0.0
                }
            })
            .collect(),
    )
}

/// An error unless `image` lies on the grid of `input`'s tracing (what
/// every image method checks before reading it).
pub(crate) fn check_grid(image: &Volume<f32>, input: &SparseMask<'_>) -> Result<(), InterpError> {
    let (a, b) = (image.geometry(), input.mask.geometry());
    if a.dims != b.dims {
        return Err(InterpError::Input(format!(
            "the image is {:?} voxels but the tracing is {:?}: the image must lie on the tracing's grid",
            a.dims, b.dims
        )));
    }
    Ok(())
}

/// The intensities of any voxel type as `f32` (the values unchanged, not rescaled).
pub fn intensity_f32(v: &AnyVolume) -> Volume<f32> {
    match v {
        AnyVolume::U8(v) => v.map(f32::from),
        AnyVolume::U16(v) => v.map(f32::from),
        AnyVolume::I16(v) => v.map(f32::from),
        AnyVolume::F32(v) => v.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two prior objects on a 7 × 1 row (pixels 0–1 and 5–6) and a walk
    /// that says inside on the whole row, bridging them.
    fn bridged() -> (Vec<f32>, Vec<f32>, Plane) {
        let phi = vec![-1.0, -1.0, 1.0, 2.0, 1.0, -1.0, -1.0];
        let z = vec![1.0; 7];
        let plane = Plane {
            width: 7,
            height: 1,
            spacing: [1.0, 1.0],
            slice_spacing: 1.0,
        };
        (phi, z, plane)
    }

    #[test]
    fn the_box_walk_joins_the_pieces_of_a_field_and_keeps_other_objects_apart() {
        let (phi, z, plane) = bridged();
        // A field of pieces, on the whole box: the walk as it stands.
        assert_eq!(
            walk_mask(true, &phi, &z, &plane, f32::INFINITY),
            vec![true; 7]
        );
        // Not a field: the pixels touching the other object are dropped, so
        // the two stay apart.
        let apart = walk_mask(false, &phi, &z, &plane, f32::INFINITY);
        assert!(apart[0] && apart[1] && apart[5] && apart[6]);
        assert!((2..5).any(|i| !apart[i]), "{apart:?}");
        // A field in the band walk (finite reach): kept apart too.
        assert_eq!(
            walk_mask(true, &phi, &z, &plane, 1.0),
            separate(&phi, &z, &plane, 1.0)
        );
    }

    #[test]
    fn a_walk_counts_as_diluted_only_inside_the_traced_span_across_gaps_of_three_or_more() {
        use interslice_core::{Axis, Geometry, LengthUnit};
        // Shown on the drawn slices 0, 2 and 5, not on 9: slice 1 lies in a
        // gap of 2, slices 3–4 in a gap of 3, slices 6–8 where it ends.
        let mut mask =
            Mask::zeros(Geometry::new([2, 2, 10], [1.0; 3], LengthUnit::Millimetre).unwrap());
        for d in [0, 2, 5] {
            mask.set_slice(Axis::Z, d, &[true; 4]).unwrap();
        }
        let drawn = [0usize, 2, 5, 9];
        let input = SparseMask::new(&mask, Axis::Z, &drawn);
        let spans = spanned(&input).unwrap();
        let got: Vec<usize> = (0..10).filter(|&s| spans(s)).collect();
        assert_eq!(got, vec![3, 4]);
    }
}
