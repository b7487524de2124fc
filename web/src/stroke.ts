/**
 * Freehand contour recording: the tracing rules of the original program.
 *
 * - Pen (or mouse, or finger) down starts the current contour, drawn red.
 * - Lifting and putting the pen down again before *Add contour* restarts the
 *   current contour: the earlier attempt is discarded.
 * - Lifting the pen on a closed path (the stroke came back to its start)
 *   finishes the contour at once; *Add contour* finishes an open one by
 *   joining its end to its start. A finished contour is sent and shown yellow.
 *
 * Every pen sample counts: callers pass all coalesced pointer events, and
 * duplicates (same position) are dropped, keeping the later pressure.
 */
import type { Vec2 } from "./transform";

/** One pen sample in slice coordinates. */
export interface Sample {
  /** Slice u. */
  u: number;
  /** Slice v. */
  v: number;
  /** Pen pressure 0..1 (0.5 for devices without pressure, as Pointer Events report). */
  p: number;
  /** Event time in ms (any epoch; made relative to the stroke start). */
  t: number;
}

/** A finished contour ready to be sent. */
export interface FinishedContour {
  /** Closed polyline; the closing edge is implicit (last point is not repeated). */
  points: Vec2[];
  /** Pressure per point (only for pens). */
  pressure?: number[];
  /** Milliseconds since the first point, per point. */
  times_ms?: number[];
  /** `pen`, `mouse` or `touch`. */
  tool: string;
}

/** What a pen lift did. */
export type LiftResult = { kind: "closed"; contour: FinishedContour } | { kind: "open" } | { kind: "none" };

/** Distance between two samples. */
function dist(a: { u: number; v: number }, b: { u: number; v: number }): number {
  return Math.hypot(a.u - b.u, a.v - b.v);
}

/** Twice the signed area of a polygon (shoelace). */
export function signedArea2(points: Vec2[]): number {
  let s = 0;
  for (let i = 0, n = points.length; i < n; i++) {
    const [x0, y0] = points[i];
    const [x1, y1] = points[(i + 1) % n];
    s += x0 * y1 - x1 * y0;
  }
  return s;
}

/**
 * Where a stroke closes: the index of the sample nearest the start among
 * those after the stroke first went farther than `3 * tol` from it, if that
 * sample is within `tol`. Samples after it (an overshoot past the start) are
 * not part of the contour. Returns -1 when the stroke is open.
 */
export function closureIndex(samples: { u: number; v: number }[], tol: number): number {
  if (samples.length < 3) return -1;
  const s0 = samples[0];
  let i = 1;
  while (i < samples.length && dist(samples[i], s0) <= 3 * tol) i++;
  if (i >= samples.length) return -1;
  let best = -1;
  let bestD = Infinity;
  for (; i < samples.length; i++) {
    const d = dist(samples[i], s0);
    if (d <= tol && d < bestD) {
      bestD = d;
      best = i;
    }
  }
  return best;
}

/** Turn samples into a contour; null when they enclose no area. */
export function toContour(samples: Sample[], tool: string): FinishedContour | null {
  // The closing point is the start again: drop a last point that duplicates it.
  let pts = samples;
  while (pts.length > 1 && dist(pts[pts.length - 1], pts[0]) < 1e-9) pts = pts.slice(0, -1);
  if (pts.length < 3) return null;
  const points: Vec2[] = pts.map((s) => [s.u, s.v]);
  if (Math.abs(signedArea2(points)) < 1e-9) return null;
  const t0 = pts[0].t;
  const c: FinishedContour = {
    points,
    times_ms: pts.map((s) => Math.max(0, Math.round((s.t - t0) * 1000) / 1000)),
    tool,
  };
  if (tool === "pen") c.pressure = pts.map((s) => s.p);
  return c;
}

/** The state machine of one slice's current contour. */
export class StrokeRecorder {
  private samples: Sample[] = [];
  private down = false;
  private tool = "mouse";

  /**
   * @param closeTol distance in slice pixels under which a stroke that came
   *   back to its start counts as closed (callers derive it from screen pixels
   *   and the zoom so closing feels the same at every zoom).
   */
  constructor(public closeTol = 3) {}

  /** The current (red) contour's samples. */
  get current(): readonly Sample[] {
    return this.samples;
  }

  /** Whether the pen is on the surface. */
  get drawing(): boolean {
    return this.down;
  }

  /** Whether there is an unfinished contour (drawn, not yet added). */
  get pending(): boolean {
    return this.samples.length > 0;
  }

  /** Pen down: (re)starts the current contour. */
  penDown(s: Sample, tool: string): void {
    this.samples = [];
    this.tool = tool;
    this.down = true;
    this.push(s);
  }

  /** Pen moved: all coalesced samples of one pointer event, in order. */
  penMove(samples: Sample[]): void {
    if (!this.down) return;
    for (const s of samples) this.push(s);
  }

  /** Pen up: finishes the contour when the path is closed. */
  penUp(s?: Sample): LiftResult {
    if (!this.down) return { kind: "none" };
    if (s) this.push(s);
    this.down = false;
    const ci = closureIndex(this.samples, this.closeTol);
    if (ci >= 0) {
      const c = toContour(this.samples.slice(0, ci + 1), this.tool);
      this.samples = [];
      return c ? { kind: "closed", contour: c } : { kind: "none" };
    }
    return { kind: "open" };
  }

  /** *Add contour*: finishes the current contour by closing it; null if it has no area. */
  finish(): FinishedContour | null {
    if (this.samples.length === 0) return null;
    const ci = closureIndex(this.samples, this.closeTol);
    const use = ci >= 0 ? this.samples.slice(0, ci + 1) : this.samples;
    const c = toContour(use, this.tool);
    this.samples = [];
    this.down = false;
    return c;
  }

  /** Drop the current contour (Escape, slice change). */
  cancel(): void {
    this.samples = [];
    this.down = false;
  }

  private push(s: Sample): void {
    if (!Number.isFinite(s.u) || !Number.isFinite(s.v)) return;
    const last = this.samples[this.samples.length - 1];
    if (last && last.u === s.u && last.v === s.v) {
      last.p = s.p;
      return;
    }
    this.samples.push({ ...s });
  }
}

/** The subset of a PointerEvent this module reads (so tests can pass plain objects). */
export interface PointerLike {
  clientX: number;
  clientY: number;
  pressure: number;
  timeStamp: number;
  pointerType: string;
  getCoalescedEvents?: () => PointerLike[];
}

/**
 * All samples of a pointer event: its coalesced events when the browser
 * provides them (a pen reports at 200+ Hz while events fire once per frame),
 * else the event itself. `toSlice` maps client coordinates to slice ones.
 */
export function samplesOf(e: PointerLike, toSlice: (cx: number, cy: number) => Vec2): Sample[] {
  let evs: PointerLike[] = [];
  if (typeof e.getCoalescedEvents === "function") {
    try {
      evs = e.getCoalescedEvents();
    } catch {
      evs = [];
    }
  }
  if (evs.length === 0) evs = [e];
  return evs.map((ev) => {
    const [u, v] = toSlice(ev.clientX, ev.clientY);
    // Mouse reports 0.5 while a button is down and 0 otherwise; keep 0.5 for non-pens.
    const p = e.pointerType === "pen" ? ev.pressure : 0.5;
    return { u, v, p, t: ev.timeStamp };
  });
}
