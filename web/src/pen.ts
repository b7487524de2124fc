/**
 * The pen on the working view: strokes become the red contour, a lift on
 * its start point (or *Add contour*) closes it and hands it on to be saved.
 * Also measures the stroke latency: from each pointer event to the frame
 * that shows it.
 */
import type { SliceView } from "./sliceview";
import { StrokeRecorder, type FinishedContour, type Sample } from "./stroke";
import type { Axis } from "./transform";

/** What the pen needs from the screen. */
export interface PenHost {
  /** The axis of the working view (the only one drawn on). */
  workingAxis(): Axis;
  /** Repaint view `a` (the red contour changed). */
  paint(a: Axis): void;
  /** A contour was closed: save it. */
  commit(c: FinishedContour): void;
  /** The user did something (for the time tracking). */
  touch(): void;
  /** ms from a pointer event to the frame that showed it. */
  latency(ms: number): void;
}

/** Closing feels the same at every zoom: this many screen pixels. */
const CLOSE_PX = 10;

/** The pen of the tracing screen. */
export class Pen {
  private recorder = new StrokeRecorder(3);
  private moveEventTimes: number[] = [];

  constructor(private host: PenHost) {}

  /** The red contour being drawn, if any. */
  get stroke(): readonly Sample[] | null {
    return this.recorder.pending ? this.recorder.current : null;
  }

  penDown(v: SliceView, s: Sample, tool: string): void {
    this.host.touch();
    if (v.axis !== this.host.workingAxis()) return;
    this.recorder.closeTol = CLOSE_PX / (v.t?.scale ?? 1);
    this.recorder.penDown(s, tool);
    this.host.paint(v.axis);
  }

  penMove(v: SliceView, s: Sample[], t: number): void {
    this.host.touch();
    this.recorder.penMove(s);
    this.moveEventTimes.push(t);
    this.host.paint(v.axis);
  }

  penUp(v: SliceView, s: Sample | undefined): void {
    const r = this.recorder.penUp(s);
    if (r.kind === "closed") this.host.commit(r.contour);
    this.host.paint(v.axis);
  }

  /** *Add contour*: finish the red contour (closing it) and save it. */
  finish(): void {
    const c = this.recorder.finish();
    if (c) this.host.commit(c);
    this.host.paint(this.host.workingAxis());
  }

  /** Discard the red contour. */
  cancel(): void {
    this.recorder.cancel();
  }

  /** Discard the red contour if there is one (before moving to another slice). */
  cancelPending(): void {
    if (this.recorder.pending) this.recorder.cancel();
  }

  /** A view painted a frame at `now`. */
  painted(now: number): void {
    for (const t of this.moveEventTimes) this.host.latency(now - t);
    this.moveEventTimes = [];
  }
}
