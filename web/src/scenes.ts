/**
 * What the slice views paint besides the image: on the working view the
 * contours of its slice (the label being traced in bold yellow, the others in
 * their colour), the dashed preview on skipped slices and, when asked, the
 * tint of its uncertain pixels; on the other two
 * views the strips where the working axis' contours cut their plane.
 */
import type { Contour, InterpResult } from "./api";
import { scanlineIntervals } from "./geometry";
import type { PaintContour, PaintRect, PaintTint } from "./sliceview";
import { axisDim, inPlane, type Axis, type Vec2 } from "./transform";
import { AXES } from "./viewstate";

/** Colours of the crosshair lines that stand for each axis' slice. */
export const AXIS_COLOR: Record<Axis, string> = { x: "#ff6b6b", y: "#6bff8a", z: "#6bb5ff" };
/** Colour of finished contours of the current label. */
const FINISHED = "#ffd54a";

/** The tracings a scene is made from. */
export interface Traced {
  /** The contours (pending changes applied). */
  contours: readonly Contour[];
  /** The preview results with their labels. */
  previews: Iterable<[number, InterpResult]>;
  /** The working axis. */
  axis: Axis;
  /** The label being traced. */
  label: number;
  /** A label's colour. */
  colorOf(label: number): string;
}

/** The crosshair of view `a` at the focus voxel. */
export function crosshair(a: Axis, focus: readonly number[]): { u: number; v: number; colorU: string; colorV: string } {
  const [du, dv] = inPlane(a);
  return { u: focus[du] + 0.5, v: focus[dv] + 0.5, colorU: AXIS_COLOR[AXES[du]], colorV: AXIS_COLOR[AXES[dv]] };
}

/**
 * The contours of working slice `idx`: drawn ones solid, interpolated ones
 * dashed (not for the traced label on a slice it drew: `drawnHere`).
 */
export function workingContours(t: Traced, idx: number, drawnHere: boolean): PaintContour[] {
  const a = t.axis;
  const cs: PaintContour[] = [];
  for (const c of t.contours) {
    if (c.axis !== a || c.index !== idx) continue;
    const cur = c.label === t.label;
    cs.push({ points: c.points, color: cur ? FINISHED : t.colorOf(c.label), width: cur ? 2 : 1.5 });
  }
  for (const [label, res] of t.previews) {
    if (res.axis !== a) continue;
    const s = res.slices.find((x) => x.index === idx);
    if (!s || s.drawn) continue;
    if (label === t.label && drawnHere) continue;
    for (const p of s.contours)
      cs.push({ points: p, color: t.colorOf(label), width: label === t.label ? 2 : 1.2, dashed: true });
  }
  return cs;
}

/** The translucent warm tint of the uncertain pixels, under the preview contour. */
export const UNCERTAIN_TINT = "rgba(255, 140, 0, 0.4)";

/**
 * The uncertain outlines of working slice `idx` ("Show uncertainty"): one
 * tint per preview that has them there (skipped slices only: the server
 * sends none for drawn ones, and none is shown for the traced label on a
 * slice it has just drawn, `drawnHere`), filled even-odd so a band's inner
 * outline stays a hole.
 */
export function uncertainTints(t: Traced, idx: number, drawnHere: boolean): PaintTint[] {
  const tints: PaintTint[] = [];
  for (const [label, res] of t.previews) {
    if (res.axis !== t.axis) continue;
    const s = res.slices.find((x) => x.index === idx);
    if (!s || s.drawn || !s.uncertain || s.uncertain.length === 0) continue;
    if (label === t.label && drawnHere) continue;
    tints.push({ polys: s.uncertain, color: UNCERTAIN_TINT });
  }
  return tints;
}

/**
 * Where the working axis' contours (drawn and interpolated) cut the plane of
 * view `b` at the focus: one thin strip per working slice, filled in the
 * label colour.
 */
export function cutRects(t: Traced, b: Axis, focus: readonly number[]): PaintRect[] {
  const A = t.axis;
  const [au, av] = inPlane(A);
  const [bu] = inPlane(b);
  const db = axisDim(b);
  const at = focus[db] + 0.5;
  // Along which in-plane dim of A the cut runs.
  const swap = db === au; // b fixes A's u: scan the polygons with u and v exchanged
  const alongDim = swap ? av : au;
  const rects: PaintRect[] = [];
  const bySlice = new Map<string, { label: number; index: number; polys: Vec2[][]; drawn: boolean }>();
  for (const c of t.contours) {
    if (c.axis !== A) continue;
    const k = `${c.label}/${c.index}`;
    const e = bySlice.get(k) ?? { label: c.label, index: c.index, polys: [], drawn: true };
    e.polys.push(c.points);
    bySlice.set(k, e);
  }
  for (const [label, res] of t.previews) {
    if (res.axis !== A) continue;
    for (const s of res.slices) {
      if (s.drawn || bySlice.has(`${label}/${s.index}`)) continue;
      bySlice.set(`${label}/${s.index}`, { label, index: s.index, polys: s.contours, drawn: false });
    }
  }
  for (const e of bySlice.values()) {
    const polys = swap ? e.polys.map((p) => p.map(([x, y]) => [y, x] as Vec2)) : e.polys;
    const color = t.colorOf(e.label) + (e.drawn ? "cc" : "66");
    for (const [s0, s1] of scanlineIntervals(polys, at)) {
      // In view b, `alongDim` and A's dim are its u and v in some order.
      if (alongDim === bu) rects.push({ r: [s0, e.index, s1, e.index + 1], color });
      else rects.push({ r: [e.index, s0, e.index + 1, s1], color });
    }
  }
  return rects;
}
