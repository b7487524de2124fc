/**
 * One slice view: a canvas showing slice `index` along `axis` with the
 * window/level applied, the crosshairs of the other two views, contours,
 * the dashed interpolation preview, the FP/FN overlay and the red contour
 * being drawn. Pointer input is turned into slice coordinates here and
 * handed to the owner through callbacks.
 */
import { getStroke } from "perfect-freehand";
import {
  canvasToSlice,
  fitTransform,
  panBy,
  sliceToCanvas,
  zoomAt,
  type Axis,
  type Vec2,
  type ViewTransform,
} from "./transform";
import type { Sample } from "./stroke";
import { samplesOf } from "./stroke";
import type { RawPixels } from "./windowing";

/** A decoded slice image ready to paint. */
export interface SliceImage {
  /** Pixels per row. */
  width: number;
  /** Rows. */
  height: number;
  /** Raw intensities in the volume's voxel type (for the status line). */
  raw: RawPixels;
  /** The windowed grey picture at native resolution. */
  bitmap: HTMLCanvasElement;
  /** The LUT version the bitmap was made with. */
  lutVersion: number;
}

/** A polygon to paint with its style. */
export interface PaintContour {
  /** Closed polyline in slice coordinates. */
  points: Vec2[];
  /** CSS colour. */
  color: string;
  /** Line width in CSS pixels. */
  width: number;
  /** Dashed (interpolated preview). */
  dashed?: boolean;
  /** Fill alpha (0 = outline only). */
  fill?: number;
}

/** Polygons filled together (even-odd: an outline inside another is a hole), no stroke. */
export interface PaintTint {
  /** Closed polylines in slice coordinates. */
  polys: Vec2[][];
  /** CSS colour (with its alpha). */
  color: string;
}

/** An axis-aligned filled rectangle in slice coordinates (cuts of other-axis contours). */
export interface PaintRect {
  /** u0, v0, u1, v1 */
  r: [number, number, number, number];
  /** CSS colour. */
  color: string;
}

/** Everything a view paints besides its image. */
export interface Scene {
  /** Crosshair positions (slice u and v of the other two views' slice centres). */
  cross: { u: number; v: number; colorU: string; colorV: string } | null;
  /** Tints painted under the contours (the uncertain pixels of the preview). */
  tints: PaintTint[];
  /** Contours to paint. */
  contours: PaintContour[];
  /** Rectangles to paint. */
  rects: PaintRect[];
  /** The red contour being drawn. */
  stroke: readonly Sample[] | null;
  /** Whether the stroke came from a pen (then its width follows pressure). */
  strokePen: boolean;
  /** FP/FN overlay of this slice: 0 TN, 1 TP, 2 FP, 3 FN per pixel. */
  overlay: Uint8Array | null;
  /** Text in the view's corner. */
  caption: string;
  /** Its colour: the axis' colour, the one its crosshair line has in the other views. */
  captionColor: string;
  /** Whether this is the working view. */
  working: boolean;
}

/** Callbacks of a view. */
export interface ViewHandlers {
  /** Pen/mouse/finger down on the working view (slice coords). */
  penDown(view: SliceView, s: Sample, tool: string): void;
  /** Pen moved while down (all coalesced samples); `eventTime` is the newest event's timeStamp. */
  penMove(view: SliceView, s: Sample[], eventTime: number): void;
  /** Pen up. */
  penUp(view: SliceView, s: Sample | undefined): void;
  /** Click on a non-working view: move the crosshair there. */
  pick(view: SliceView, u: number, v: number): void;
  /** The cursor moved (or left: null). */
  hover(view: SliceView, u: number, v: number, inside: boolean): void;
  /** Transform changed (zoom/pan). */
  changed(view: SliceView): void;
}

/** One orthogonal view. */
export class SliceView {
  /** The canvas (data-testid `view-<axis>`). */
  readonly canvas: HTMLCanvasElement;
  /** The current transform; null until laid out. */
  t: ViewTransform | null = null;
  /** Whether the user zoomed/panned (then a resize keeps the zoom). */
  private userMoved = false;
  /** The image shown. */
  image: SliceImage | null = null;
  /** Physical aspect of a pixel (spacing_v / spacing_u). */
  aspect = 1;
  /** Slice size. */
  size: [number, number] = [1, 1];
  /** Slice index shown. */
  index = 0;
  /** The scene painted over the image. */
  scene: Scene = {
    cross: null,
    tints: [],
    contours: [],
    rects: [],
    stroke: null,
    strokePen: false,
    overlay: null,
    caption: "",
    captionColor: "#ccc",
    working: false,
  };
  private panning: { x: number; y: number; id: number } | null = null;
  private drawingId: number | null = null;
  private spaceDown = false;
  private overlayCanvas: HTMLCanvasElement | null = null;
  private overlaySrc: Uint8Array | null = null;
  private raf = 0;
  /** Time of the last paint (performance.now()), for latency figures. */
  lastPaint = 0;
  /** Called after each paint with the paint time. */
  onPaint: (now: number) => void = () => {};

  constructor(
    public readonly axis: Axis,
    private handlers: ViewHandlers,
  ) {
    this.canvas = document.createElement("canvas");
    this.canvas.className = `view view-${axis}`;
    this.canvas.setAttribute("data-testid", `view-${axis}`);
    this.canvas.tabIndex = 0;
    this.bind();
  }

  /** Client (page) coordinates -> slice coordinates. */
  clientToSlice(cx: number, cy: number): Vec2 {
    const r = this.canvas.getBoundingClientRect();
    const t = this.t ?? { scale: 1, aspect: 1, ox: 0, oy: 0 };
    return canvasToSlice(t, cx - r.left, cy - r.top);
  }

  /** Slice coordinates -> client (page) coordinates (used by tests and tools). */
  sliceToClient(u: number, v: number): Vec2 {
    const r = this.canvas.getBoundingClientRect();
    const t = this.t ?? { scale: 1, aspect: 1, ox: 0, oy: 0 };
    const [x, y] = sliceToCanvas(t, u, v);
    return [x + r.left, y + r.top];
  }

  /** Set the slice geometry; resets the zoom when it changed. */
  setGeometry(width: number, height: number, aspect: number): void {
    if (this.size[0] !== width || this.size[1] !== height || this.aspect !== aspect) {
      this.size = [width, height];
      this.aspect = aspect;
      this.userMoved = false;
      this.t = null;
    }
  }

  /** Fit the slice to the canvas. */
  fit(): void {
    this.userMoved = false;
    this.t = null;
    this.layout();
    this.requestPaint();
  }

  /** Zoom by a factor about the canvas centre. */
  zoom(factor: number): void {
    this.layout();
    if (!this.t) return;
    const r = this.canvas.getBoundingClientRect();
    this.t = zoomAt(this.t, r.width / 2, r.height / 2, factor);
    this.userMoved = true;
    this.handlers.changed(this);
    this.requestPaint();
  }

  /** Match the canvas backing store to its CSS size and fit if needed. */
  layout(): void {
    const r = this.canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width * dpr));
    const hgt = Math.max(1, Math.round(r.height * dpr));
    if (this.canvas.width !== w || this.canvas.height !== hgt) {
      this.canvas.width = w;
      this.canvas.height = hgt;
      if (!this.userMoved) this.t = null;
    }
    if (!this.t && r.width > 0) this.t = fitTransform(this.size[0], this.size[1], this.aspect, r.width, r.height);
  }

  /** Set the FP/FN overlay (re-made into a picture only when it changed). */
  setOverlay(o: Uint8Array | null): void {
    this.scene.overlay = o;
  }

  /** Paint at the next animation frame. */
  requestPaint(): void {
    if (this.raf) return;
    this.raf = requestAnimationFrame(() => {
      this.raf = 0;
      this.paint();
    });
  }

  /** Paint now. */
  paint(): void {
    this.layout();
    const ctx = this.canvas.getContext("2d");
    if (!ctx || !this.t) return;
    const dpr = window.devicePixelRatio || 1;
    const t = this.t;
    const [w, hgt] = this.size;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#111";
    ctx.fillRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const [x0, y0] = sliceToCanvas(t, 0, 0);
    const [x1, y1] = sliceToCanvas(t, w, hgt);
    if (this.image) {
      ctx.imageSmoothingEnabled = false;
      ctx.drawImage(this.image.bitmap, x0, y0, x1 - x0, y1 - y0);
    }
    const sc = this.scene;
    if (sc.overlay && sc.overlay.length === w * hgt) {
      if (this.overlaySrc !== sc.overlay || !this.overlayCanvas) this.makeOverlay(sc.overlay, w, hgt);
      if (this.overlayCanvas) {
        ctx.imageSmoothingEnabled = false;
        ctx.drawImage(this.overlayCanvas, x0, y0, x1 - x0, y1 - y0);
      }
    }
    for (const r of sc.rects) {
      const [a, b] = sliceToCanvas(t, r.r[0], r.r[1]);
      const [c, d] = sliceToCanvas(t, r.r[2], r.r[3]);
      ctx.fillStyle = r.color;
      ctx.fillRect(a, b, c - a, d - b);
    }
    for (const tint of sc.tints) this.paintTint(ctx, tint);
    for (const c of sc.contours) this.paintPolygon(ctx, c);
    if (sc.cross) {
      const [cx, cy] = sliceToCanvas(t, sc.cross.u, sc.cross.v);
      ctx.lineWidth = 1;
      ctx.setLineDash([4, 4]);
      ctx.strokeStyle = sc.cross.colorU;
      ctx.beginPath();
      ctx.moveTo(cx, y0);
      ctx.lineTo(cx, y1);
      ctx.stroke();
      ctx.strokeStyle = sc.cross.colorV;
      ctx.beginPath();
      ctx.moveTo(x0, cy);
      ctx.lineTo(x1, cy);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    if (sc.stroke && sc.stroke.length > 0) this.paintStroke(ctx, sc.stroke, sc.strokePen);
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.font = `${12 * dpr}px system-ui, sans-serif`;
    ctx.fillStyle = sc.captionColor;
    ctx.fillText(sc.caption, 6 * dpr, 16 * dpr);
    this.lastPaint = performance.now();
    this.onPaint(this.lastPaint);
  }

  private makeOverlay(o: Uint8Array, w: number, hgt: number): void {
    const c = this.overlayCanvas ?? document.createElement("canvas");
    c.width = w;
    c.height = hgt;
    const ctx = c.getContext("2d");
    if (!ctx) return;
    const img = ctx.createImageData(w, hgt);
    const d = img.data;
    for (let p = 0, q = 0; p < o.length; p++, q += 4) {
      const k = o[p];
      if (k === 2) {
        // False positive: magenta.
        d[q] = 255;
        d[q + 1] = 0;
        d[q + 2] = 200;
        d[q + 3] = 120;
      } else if (k === 3) {
        // False negative: cyan.
        d[q] = 0;
        d[q + 1] = 200;
        d[q + 2] = 255;
        d[q + 3] = 120;
      } else if (k === 1) {
        // True positive: faint green.
        d[q] = 0;
        d[q + 1] = 255;
        d[q + 2] = 0;
        d[q + 3] = 40;
      }
    }
    ctx.putImageData(img, 0, 0);
    this.overlayCanvas = c;
    this.overlaySrc = o;
  }

  private paintTint(ctx: CanvasRenderingContext2D, tint: PaintTint): void {
    if (!this.t) return;
    ctx.beginPath();
    for (const poly of tint.polys) {
      poly.forEach(([u, v], i) => {
        const [x, y] = sliceToCanvas(this.t!, u, v);
        if (i === 0) ctx.moveTo(x, y);
        else ctx.lineTo(x, y);
      });
      ctx.closePath();
    }
    ctx.fillStyle = tint.color;
    ctx.fill("evenodd");
  }

  private paintPolygon(ctx: CanvasRenderingContext2D, c: PaintContour): void {
    if (!this.t || c.points.length < 2) return;
    ctx.beginPath();
    c.points.forEach(([u, v], i) => {
      const [x, y] = sliceToCanvas(this.t!, u, v);
      if (i === 0) ctx.moveTo(x, y);
      else ctx.lineTo(x, y);
    });
    ctx.closePath();
    if (c.fill) {
      ctx.globalAlpha = c.fill;
      ctx.fillStyle = c.color;
      ctx.fill("evenodd");
      ctx.globalAlpha = 1;
    }
    ctx.lineWidth = c.width;
    ctx.strokeStyle = c.color;
    ctx.setLineDash(c.dashed ? [6, 4] : []);
    ctx.stroke();
    ctx.setLineDash([]);
  }

  private paintStroke(ctx: CanvasRenderingContext2D, s: readonly Sample[], pen: boolean): void {
    const t = this.t!;
    const pts = s.map((p) => {
      const [x, y] = sliceToCanvas(t, p.u, p.v);
      return [x, y, p.p];
    });
    ctx.fillStyle = "#ff2a2a";
    if (pts.length === 1) {
      ctx.beginPath();
      ctx.arc(pts[0][0], pts[0][1], 2, 0, 2 * Math.PI);
      ctx.fill();
      return;
    }
    // A smooth variable-width ink for the eye; the stored contour is the raw samples.
    const outline = getStroke(pts, {
      size: 4,
      thinning: pen ? 0.5 : 0,
      smoothing: 0.5,
      streamline: 0.2,
      simulatePressure: false,
      last: false,
    });
    if (outline.length < 3) return;
    ctx.beginPath();
    ctx.moveTo(outline[0][0], outline[0][1]);
    for (let i = 1; i < outline.length; i++) ctx.lineTo(outline[i][0], outline[i][1]);
    ctx.closePath();
    ctx.fill();
  }

  private bind(): void {
    const c = this.canvas;
    c.style.touchAction = "none";
    c.addEventListener("contextmenu", (e) => e.preventDefault());
    c.addEventListener("keydown", (e) => {
      if (e.key === " ") {
        this.spaceDown = true;
        e.preventDefault();
      }
    });
    c.addEventListener("keyup", (e) => {
      if (e.key === " ") this.spaceDown = false;
    });
    c.addEventListener("pointerdown", (e) => {
      c.focus({ preventScroll: true });
      const panButton = e.button === 1 || e.button === 2 || (e.button === 0 && (this.spaceDown || e.altKey));
      if (panButton) {
        this.panning = { x: e.clientX, y: e.clientY, id: e.pointerId };
        c.setPointerCapture(e.pointerId);
        e.preventDefault();
        return;
      }
      if (e.button !== 0) return;
      const [u, v] = this.clientToSlice(e.clientX, e.clientY);
      if (!this.scene.working) {
        this.handlers.pick(this, u, v);
        return;
      }
      if (this.drawingId !== null) return; // a second finger: ignore
      this.drawingId = e.pointerId;
      c.setPointerCapture(e.pointerId);
      e.preventDefault();
      const p = e.pointerType === "pen" ? e.pressure : 0.5;
      this.handlers.penDown(this, { u, v, p, t: e.timeStamp }, e.pointerType || "mouse");
    });
    c.addEventListener("pointermove", (e) => {
      if (this.panning && e.pointerId === this.panning.id) {
        if (this.t) this.t = panBy(this.t, e.clientX - this.panning.x, e.clientY - this.panning.y);
        this.panning.x = e.clientX;
        this.panning.y = e.clientY;
        this.userMoved = true;
        this.handlers.changed(this);
        this.requestPaint();
        return;
      }
      if (this.drawingId === e.pointerId) {
        this.handlers.penMove(
          this,
          samplesOf(e, (x, y) => this.clientToSlice(x, y)),
          e.timeStamp,
        );
      }
      const [u, v] = this.clientToSlice(e.clientX, e.clientY);
      this.handlers.hover(this, u, v, true);
    });
    const end = (e: PointerEvent) => {
      if (this.panning && e.pointerId === this.panning.id) {
        this.panning = null;
        return;
      }
      if (this.drawingId === e.pointerId) {
        this.drawingId = null;
        const [u, v] = this.clientToSlice(e.clientX, e.clientY);
        const p = e.pointerType === "pen" ? e.pressure : 0.5;
        this.handlers.penUp(this, e.type === "pointerup" ? { u, v, p, t: e.timeStamp } : undefined);
      }
    };
    c.addEventListener("pointerup", end);
    c.addEventListener("pointercancel", end);
    c.addEventListener("pointerleave", (e) => {
      if (this.drawingId === null) {
        const [u, v] = this.clientToSlice(e.clientX, e.clientY);
        this.handlers.hover(this, u, v, false);
      }
    });
    c.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        this.layout();
        if (!this.t) return;
        const r = c.getBoundingClientRect();
        const f = Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015));
        this.t = zoomAt(this.t, e.clientX - r.left, e.clientY - r.top, f);
        this.userMoved = true;
        this.handlers.changed(this);
        this.requestPaint();
      },
      { passive: false },
    );
  }
}
