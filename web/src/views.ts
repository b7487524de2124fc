/**
 * The three linked orthogonal views of a cell: the working view in the big
 * slot and the other two beside it, each showing the slice through the focus
 * voxel with the crosshairs of the others. Slices come from the slice cache;
 * what is painted over them comes from the owner (`ViewsHost.overlay`).
 */
import type { CellDetail, RawSlice } from "./api";
import { AXIS_COLOR, crosshair } from "./scenes";
import { SliceCache } from "./slicecache";
import { SliceView, type PaintContour, type PaintRect, type PaintTint, type ViewHandlers } from "./sliceview";
import type { Sample } from "./stroke";
import { axisDim, inPlane, sliceShape, type Axis, type Vec2 } from "./transform";
import { AXES } from "./viewstate";
import type { Window } from "./windowing";

/** What a view paints over its slice. */
export interface Overlay {
  /** Tints under the contours (the preview's uncertain pixels, working view only). */
  tints: PaintTint[];
  contours: PaintContour[];
  rects: PaintRect[];
  /** The red contour being drawn (working view only). */
  stroke: readonly Sample[] | null;
  /** FP/FN overlay of the slice. */
  evaluation: Uint8Array | null;
}

/** What the views need from their owner. */
export interface ViewsHost {
  /** Pointer input. */
  handlers: ViewHandlers;
  /** The working axis and the focus voxel. */
  focus(): { axis: Axis; focus: readonly number[] };
  /** What view `a` paints over slice `idx`. */
  overlay(a: Axis, idx: number, working: boolean): Overlay;
  /** A frame was painted at `now` (for stroke latency). */
  painted(now: number): void;
  /** A slice could not be loaded. */
  failed(msg: string): void;
}

/** The slots the views go in. */
export interface ViewSlots {
  main: HTMLElement;
  sideA: HTMLElement;
  sideB: HTMLElement;
}

/** The three views. */
export class LinkedViews {
  readonly views: Record<Axis, SliceView>;
  private slices: SliceCache;
  private ro: ResizeObserver | null = null;

  constructor(
    cell: Pick<CellDetail, "dims" | "spacing" | "dtype">,
    fetchSlice: (axis: Axis, index: number) => Promise<RawSlice>,
    private host: ViewsHost,
  ) {
    this.slices = new SliceCache(fetchSlice, cell.dtype);
    const v = (a: Axis) => new SliceView(a, host.handlers);
    this.views = { x: v("x"), y: v("y"), z: v("z") };
    for (const a of AXES) {
      const [w, hh] = sliceShape(a, cell.dims);
      const [du, dv] = inPlane(a);
      this.views[a].setGeometry(w, hh, cell.spacing[dv] / cell.spacing[du]);
      this.views[a].onPaint = (now) => host.painted(now);
    }
  }

  /** Repaint when the views change size. */
  observeResize(): void {
    const ro = new ResizeObserver(() => AXES.forEach((a) => this.views[a].requestPaint()));
    AXES.forEach((a) => ro.observe(this.views[a].canvas));
    this.ro = ro;
  }

  /** Stop observing. */
  dispose(): void {
    this.ro?.disconnect();
  }

  /** Put the working view in the big slot, the others beside it. */
  place(slots: ViewSlots, axis: Axis): void {
    const others = AXES.filter((a) => a !== axis);
    slots.main.replaceChildren(this.views[axis].canvas);
    slots.sideA.replaceChildren(this.views[others[0]].canvas);
    slots.sideB.replaceChildren(this.views[others[1]].canvas);
    this.fit();
  }

  /** Fit every slice to its view. */
  fit(): void {
    AXES.forEach((a) => this.views[a].fit());
  }

  /** Use a new display window. */
  setWindow(win: Window): void {
    this.slices.setWindow(win);
  }

  /** Load the three views' slices and paint. */
  async refreshAll(): Promise<void> {
    await Promise.all(AXES.map((a) => this.refresh(a)));
  }

  /** Load view `a`'s slice through the focus and paint it. */
  async refresh(a: Axis): Promise<void> {
    const idx = this.host.focus().focus[axisDim(a)];
    const v = this.views[a];
    v.index = idx;
    try {
      const img = await this.slices.get(a, idx);
      if (v.index !== idx) return; // a newer request won
      v.image = img;
    } catch (e) {
      this.host.failed(`slice ${a}=${idx}: ${(e as Error).message}`);
    }
    this.paint(a);
  }

  /** Load slices ahead (errors ignored: they show when the slice is visited). */
  prefetch(a: Axis, indices: number[]): void {
    for (const j of indices) void this.slices.get(a, j).catch(() => {});
  }

  /** Repaint every view (pictures redrawn with the current window). */
  paintAll(): void {
    for (const a of AXES) {
      const img = this.views[a].image;
      if (img) this.slices.refresh(img);
      this.paint(a);
    }
  }

  /** Build a view's scene and paint it at the next frame. */
  paint(a: Axis): void {
    const v = this.views[a];
    const { axis, focus } = this.host.focus();
    const working = a === axis;
    const idx = focus[axisDim(a)];
    const o = this.host.overlay(a, idx, working);
    v.scene.working = working;
    v.scene.cross = crosshair(a, focus);
    v.scene.caption = `${a.toUpperCase()} = ${idx}${working ? "  · working view" : ""}`;
    v.scene.captionColor = AXIS_COLOR[a];
    v.scene.overlay = o.evaluation;
    v.scene.tints = o.tints;
    v.scene.contours = o.contours;
    v.scene.rects = o.rects;
    v.scene.stroke = o.stroke;
    v.requestPaint();
  }

  /** Slice -> client coordinates of a view. */
  sliceToClient(a: Axis, u: number, v: number): Vec2 {
    return this.views[a].sliceToClient(u, v);
  }
}
