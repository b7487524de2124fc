/**
 * The tracing screen of one cell: three linked orthogonal views, the tools
 * of the original program (skip, add contour, clear, mark empty, undo/redo,
 * next cell) and what goes beyond it (live interpolation preview, 3D view,
 * status line, shortcuts, offline-safe saving, evaluation panel).
 */
import { ApiError, type Api, type CellDetail, type Contour, type InterpResult, type Label, type Me, type Method } from "./api";
import { clear, h, hms } from "./dom";
import { EvalPanel } from "./evalpanel";
import { scanlineIntervals } from "./geometry";
import { applyPending, newClientId, type Outbox } from "./queue";
import { SHORTCUTS, actionOf, type Action } from "./shortcuts";
import { SliceView, type PaintContour, type PaintRect, type SliceImage } from "./sliceview";
import { StrokeRecorder, type FinishedContour, type Sample } from "./stroke";
import { axisDim, inPlane, pixelAt, sliceShape, voxelOf, type Axis, type Vec2 } from "./transform";
import { AUTO_PRESET, applyBrightnessContrast, buildLut, decodeSlice, defaultPreset, formatValue, presetsFor, presetWindow, renderGrey, windowText, type Histogram, type Lut, type Preset, type Window } from "./windowing";
import type { Viewer3D } from "./view3d";

/** Colours of the crosshair lines that stand for each axis' slice. */
const AXIS_COLOR: Record<Axis, string> = { x: "#ff6b6b", y: "#6bff8a", z: "#6bb5ff" };
const AXES: Axis[] = ["x", "y", "z"];
/** Colour of finished contours of the current label. */
const FINISHED = "#ffd54a";

/** Figures measured in the browser (read by the end-to-end test). */
export interface Figures {
  /** ms from a slice change to its picture painted. */
  sliceSwitch: number[];
  /** ms from a pointer event to the frame that shows it. */
  strokeLatency: number[];
  /** ms from finishing a contour to the updated dashed preview painted. */
  previewLatency: number[];
  /** ms from finishing a contour to the server's acknowledgement that it is stored. */
  saveLatency: number[];
}

/** Persisted per-cell view settings. */
interface ViewState {
  axis: Axis;
  focus: [number, number, number];
  skip: number;
  label: number;
  method: string;
  brightness: number;
  contrast: number;
  /** The base window: a preset id, or "manual" for `manual`. Empty: the cell's default preset. */
  preset: string;
  /** The window typed in by hand (with preset "manual"). */
  manual: Window | null;
}

/** What the app shell gives the tracer. */
export interface TracerHost {
  api: Api;
  outbox: Outbox;
  me: Me;
  /** Go to another cell. */
  openCell(id: string): void;
  /** Back to the cell list. */
  showList(): void;
  /** Report a message in the shell. */
  toast(msg: string, error?: boolean): void;
}

/** The tracing screen. */
export class Tracer {
  readonly root: HTMLElement;
  readonly figures: Figures = { sliceSwitch: [], strokeLatency: [], previewLatency: [], saveLatency: [] };
  /** Whether start() finished (the screen shows the cell and its tracings). */
  ready = false;
  /** When each unacknowledged contour was finished, by client id. */
  private committedAt = new Map<string, number>();
  private views: Record<Axis, SliceView>;
  private st: ViewState;
  private hist: Histogram | null = null;
  private baseWin: Window = { lo: 0, hi: 255 };
  private win: Window = { lo: 0, hi: 255 };
  private lut: Lut = buildLut("u8", { lo: 0, hi: 255 });
  private presets: Preset[] = [AUTO_PRESET];
  private lutVersion = 0;
  private cache = new Map<string, SliceImage>();
  private inflight = new Map<string, Promise<SliceImage>>();
  private serverContours: Contour[] = [];
  private contours: Contour[] = [];
  private drawn = new Map<number, boolean>(); // index -> empty, for current label & axis
  private previews = new Map<string, InterpResult>(); // `${label}/${axis}`
  private previewBusy = false;
  private previewAgain = false;
  private previewT0: number | null = null;
  private recorder = new StrokeRecorder(3);
  private methods: Method[] = [];
  private labels: Label[];
  private cursor: { axis: Axis; u: number; v: number } | null = null;
  private seconds = 0;
  private unsentSeconds = 0;
  private lastInput = performance.now();
  private timers: number[] = [];
  private viewer: Viewer3D | null = null;
  private show3d = false;
  private evalPanel: EvalPanel;
  private moveEventTimes: number[] = [];
  private disposed = false;
  private el: Record<string, HTMLElement> = {};
  private keyHandler = (e: KeyboardEvent) => this.onKey(e);

  constructor(
    private host: TracerHost,
    readonly cell: CellDetail,
  ) {
    this.labels = cell.labels.length ? cell.labels : [{ id: 1, name: "Cell", color: "#e6194b" }];
    this.st = this.loadState();
    const handlers = {
      penDown: (v: SliceView, s: Sample, tool: string) => this.penDown(v, s, tool),
      penMove: (v: SliceView, s: Sample[], t: number) => this.penMove(v, s, t),
      penUp: (v: SliceView, s: Sample | undefined) => this.penUp(v, s),
      pick: (v: SliceView, u: number, vv: number) => this.pick(v, u, vv),
      hover: (v: SliceView, u: number, vv: number, inside: boolean) => {
        this.cursor = inside ? { axis: v.axis, u, v: vv } : null;
        this.updateStatus();
      },
      changed: () => {},
    };
    this.views = { x: new SliceView("x", handlers), y: new SliceView("y", handlers), z: new SliceView("z", handlers) };
    for (const a of AXES) {
      const [w, hh] = sliceShape(a, cell.dims);
      const [du, dv] = inPlane(a);
      this.views[a].setGeometry(w, hh, cell.spacing[dv] / cell.spacing[du]);
    }
    // Stroke latency: from the newest pointer event to the frame that painted it.
    this.views.x.onPaint = this.views.y.onPaint = this.views.z.onPaint = (now) => {
      if (this.moveEventTimes.length) {
        for (const t of this.moveEventTimes) this.figures.strokeLatency.push(now - t);
        this.moveEventTimes = [];
      }
    };
    this.evalPanel = new EvalPanel({
      api: host.api,
      me: host.me,
      cell,
      label: () => this.st.label,
      labels: () => this.labels,
      overlayChanged: () => this.refreshOverlays(),
      toast: host.toast,
    });
    this.root = this.build();
  }

  // ---------- state ----------

  private stateKey(): string {
    return `interslice.view.${this.cell.id}`;
  }

  private loadState(): ViewState {
    const d = this.cell.dims;
    const def: ViewState = {
      axis: "z",
      focus: [Math.floor(d[0] / 2), Math.floor(d[1] / 2), Math.floor(d[2] / 2)],
      skip: 5,
      label: this.labels.find((l) => /nucleus/i.test(l.name))?.id ?? this.labels[0].id,
      method: "",
      brightness: 0,
      contrast: 0,
      preset: "",
      manual: null,
    };
    try {
      const s = JSON.parse(localStorage.getItem(this.stateKey()) ?? "null") as Partial<ViewState> | null;
      if (s && typeof s === "object") {
        const m = { ...def, ...s };
        if (!AXES.includes(m.axis)) m.axis = "z";
        m.focus = m.focus.map((f, i) => Math.min(d[i] - 1, Math.max(0, Math.round(Number(f) || 0)))) as [number, number, number];
        m.skip = Math.max(1, Math.round(Number(m.skip) || 1));
        if (!this.labels.some((l) => l.id === m.label)) m.label = def.label;
        const mw = m.manual;
        if (!(mw && Number.isFinite(mw.lo) && Number.isFinite(mw.hi) && mw.hi > mw.lo)) m.manual = null;
        if (typeof m.preset !== "string" || (m.preset === "manual" && !m.manual)) m.preset = "";
        return m;
      }
    } catch {
      /* fall back to defaults */
    }
    return def;
  }

  private saveState(): void {
    localStorage.setItem(this.stateKey(), JSON.stringify(this.st));
  }

  private get index(): number {
    return this.st.focus[axisDim(this.st.axis)];
  }

  private get depth(): number {
    return this.cell.dims[axisDim(this.st.axis)];
  }

  private labelOf(id: number): Label {
    return this.labels.find((l) => l.id === id) ?? { id, name: `Label ${id}`, color: "#cccccc" };
  }

  // ---------- DOM ----------

  private build(): HTMLElement {
    const e = this.el;
    const axisSel = h("select", { testid: "axis-select", title: "Axis to trace on (X/Y/Z)", onchange: (ev: Event) => this.setAxis((ev.target as HTMLSelectElement).value as Axis) });
    for (const a of AXES) axisSel.append(h("option", { value: a }, `${a} (${sliceShape(a, this.cell.dims)[2]} slices)`));
    e.axis = axisSel;
    e.sliceIndex = h("input", {
      testid: "slice-index",
      type: "number",
      min: "0",
      title: "Slice index (0-based); any slice can be reached",
      onchange: (ev: Event) => {
        const box = ev.target as HTMLInputElement;
        // Leave the box so the arrow keys step through slices again.
        box.blur();
        void this.goto(Number(box.value));
      },
    });
    e.sliceMax = h("span", { class: "muted" });
    e.skip = h("input", {
      testid: "skip-step",
      type: "number",
      min: "1",
      title: "Skip: Next/Previous slice jump by this many slices",
      onchange: (ev: Event) => {
        this.st.skip = Math.max(1, Math.round(Number((ev.target as HTMLInputElement).value) || 1));
        (ev.target as HTMLInputElement).value = String(this.st.skip);
        this.saveState();
      },
    });
    e.label = h("select", { testid: "label-select", title: "Component being traced (1-9)", onchange: (ev: Event) => this.setLabel(Number((ev.target as HTMLSelectElement).value)) });
    e.swatch = h("span", { class: "swatch" });
    const newLabel = h("input", { testid: "new-label-name", type: "text", placeholder: "new component", class: "grow", "aria-label": "new component name" }) as HTMLInputElement;
    e.method = h("select", { testid: "method-select", title: "Interpolation method", onchange: (ev: Event) => {
      this.st.method = (ev.target as HTMLSelectElement).value;
      this.saveState();
      this.schedulePreview();
    } });
    e.autoPreview = h("input", { type: "checkbox", checked: true, id: "auto-preview" });
    e.unsaved = h("span", { class: "unsaved" });
    e.status = h("div", { class: "statusline", testid: "status-line" });
    e.volume = h("div", { class: "muted small" });
    e.done = h("input", { type: "checkbox", id: "cell-done", checked: this.cell.status === "done", onchange: (ev: Event) => this.setDone((ev.target as HTMLInputElement).checked) });
    const bright = h("input", { testid: "brightness", type: "range", min: "-100", max: "100", value: String(this.st.brightness), title: "Brightness", oninput: (ev: Event) => {
      this.st.brightness = Number((ev.target as HTMLInputElement).value);
      this.applyWindow();
    } }) as HTMLInputElement;
    const contrast = h("input", { testid: "contrast", type: "range", min: "-100", max: "100", value: String(this.st.contrast), title: "Contrast", oninput: (ev: Event) => {
      this.st.contrast = Number((ev.target as HTMLInputElement).value);
      this.applyWindow();
    } }) as HTMLInputElement;
    e.bright = bright;
    e.contrast = contrast;
    e.wlo = h("input", { testid: "window-low", type: "number", step: "any", title: "Window low (black), in the file's units", class: "num", onchange: () => this.manualWindow() });
    e.whi = h("input", { testid: "window-high", type: "number", step: "any", title: "Window high (white), in the file's units", class: "num", onchange: () => this.manualWindow() });
    e.preset = h("select", { testid: "window-preset", title: "Window preset", onchange: (ev: Event) => this.choosePreset((ev.target as HTMLSelectElement).value) });

    const btn = (testid: string | null, text: string, title: string, action: () => void, cls = "") =>
      h("button", { testid: testid ?? undefined, title, class: cls, onclick: () => action() }, text);

    const side = h(
      "aside",
      { class: "side" },
      h("section", {},
        h("h3", {}, "Slice"),
        h("div", { class: "row" }, h("label", {}, "Axis "), axisSel),
        h("div", { class: "row" },
          btn("slice-prev", "◀ Prev", "Previous slice by the skip step (←)", () => this.step(-this.st.skip)),
          e.sliceIndex, e.sliceMax,
          btn("slice-next", "Next ▶", "Next slice by the skip step (→)", () => this.step(this.st.skip)),
        ),
        h("div", { class: "row" }, h("label", {}, "Skip "), e.skip, h("span", { class: "muted small" }, "slices per step")),
      ),
      h("section", {},
        h("h3", {}, "Component"),
        h("div", { class: "row" }, e.swatch, e.label),
        h("div", { class: "row" }, newLabel, btn("new-label-add", "Add", "Add a component", () => void this.addLabel(newLabel))),
      ),
      h("section", {},
        h("h3", {}, "Contours"),
        h("div", { class: "grid2" },
          btn("add-contour", "Add contour", "Finish the red contour and start another (Enter)", () => this.addContour(), "primary"),
          btn("clear-contours", "Clear all contours", "Clear this component's contours on this slice (C)", () => this.clearContours()),
          btn("mark-empty", "Mark empty", "The component is absent on this slice (E)", () => this.markEmpty()),
          h("span", {}),
          btn("undo", "↶ Undo", "Undo (Ctrl+Z)", () => void this.undoRedo("undo")),
          btn("redo", "↷ Redo", "Redo (Ctrl+Shift+Z)", () => void this.undoRedo("redo")),
        ),
        e.unsaved,
      ),
      h("section", {},
        h("h3", {}, "Interpolation"),
        h("div", { class: "row" }, e.method),
        h("div", { class: "row" }, e.autoPreview, h("label", { for: "auto-preview" }, "live preview on skipped slices")),
        h("div", { class: "row" }, btn("interpolate", "Interpolate", "Interpolate now (I)", () => void this.runPreview(true), "primary")),
        e.volume,
      ),
      h("section", {},
        h("h3", {}, "Display"),
        h("div", { class: "row" }, h("label", { class: "w" }, "Brightness"), bright),
        h("div", { class: "row" }, h("label", { class: "w" }, "Contrast"), contrast),
        h("div", { class: "row" }, h("label", { class: "w" }, "Preset"), e.preset),
        h("div", { class: "row" }, h("label", { class: "w" }, "Window"), e.wlo, h("span", {}, "–"), e.whi),
        h("div", { class: "row" },
          btn("auto-window", "Auto", "Automatic window from the histogram (W)", () => this.autoWin()),
          btn(null, "Fit", "Fit slices to the views (0)", () => AXES.forEach((a) => this.views[a].fit())),
          btn(null, "+", "Zoom in (+)", () => this.views[this.st.axis].zoom(1.25)),
          btn(null, "−", "Zoom out (−)", () => this.views[this.st.axis].zoom(0.8)),
        ),
      ),
      this.evalPanel.root,
      h("section", {},
        h("h3", {}, "Cell"),
        h("div", { class: "row" }, e.done, h("label", { for: "cell-done" }, "finished (hide from my queue)")),
        h("div", { class: "row" },
          btn("next-cell", "Next cell ▶", "Open the next cell in the queue (N); everything is saved", () => void this.nextCell(), "primary"),
          btn(null, "All cells", "Back to the cell list", () => this.host.showList()),
        ),
        h("div", { class: "row small" },
          "Export: ",
          ...["nii.gz", "nrrd", "seg.nrrd", "tiff", "contours"].map((f) => h("a", { href: this.host.api.exportUrl(this.cell.id, f), download: "", class: "exp" }, f)),
        ),
      ),
    );
    newLabel.addEventListener("keydown", (ev) => {
      if ((ev as KeyboardEvent).key === "Enter") void this.addLabel(newLabel);
    });

    e.main = h("div", { class: "slot-main" });
    e.sideA = h("div", { class: "slot-a" });
    e.sideB = h("div", { class: "slot-b" });
    e.v3dHost = h("div", { class: "v3d-host" });
    e.v3dMsg = h("div", { class: "v3d-msg", testid: "view-3d-status" }, "3D view — click to show the interpolated surfaces (D)");
    e.v3d = h("div", { class: "slot-3d", testid: "view-3d", title: "3D view of the interpolated surfaces (D)", onclick: () => {
      if (!this.show3d) void this.toggle3d(true);
    } }, e.v3dHost, e.v3dMsg);
    const views = h("div", { class: "views" }, e.main, e.sideA, e.sideB, e.v3d);
    e.help = this.buildHelp();
    const root = h("div", { class: "tracer" }, side, h("div", { class: "work" }, views, e.status), e.help);
    return root;
  }

  private buildHelp(): HTMLElement {
    const rows = SHORTCUTS.map((s) => h("tr", {}, h("td", {}, h("kbd", {}, s.keys)), h("td", {}, s.help)));
    const box = h(
      "div",
      { class: "help", testid: "help-overlay", hidden: true, onclick: (e: Event) => {
        if (e.target === box) box.hidden = true;
      } },
      h("div", { class: "help-box" },
        h("h2", {}, "Keyboard and pen"),
        h("table", {}, ...rows),
        h("p", { class: "small" },
          "Draw with the pen, mouse or a finger on the working view. Lift on the start point to close a contour (it turns yellow and is saved); ",
          "lift elsewhere and put the pen down again to restart the red contour; Add contour closes it. ",
          "Pan: middle or right drag, or Space/Alt + drag. Zoom: wheel. Click a small view to move the crosshair there."),
        h("button", { onclick: () => (box.hidden = true) }, "Close"),
      ),
    );
    return box;
  }

  // ---------- lifecycle ----------

  /** Load everything and show the cell. */
  async start(): Promise<void> {
    document.addEventListener("keydown", this.keyHandler);
    const api = this.host.api;
    const [hist, methods] = await Promise.all([api.histogram(this.cell.id).catch(() => null), api.methods().catch(() => [] as Method[])]);
    this.hist = hist;
    this.methods = methods;
    this.presets = presetsFor(hist, this.cell.dtype);
    this.baseWin = this.baseWindow();
    this.fillPresets();
    this.fillLabels();
    this.fillMethods();
    this.applyWindow(false);
    await this.reloadContours();
    this.placeViews();
    this.syncControls();
    await this.refreshAll();
    if (this.hasDrawn()) void this.runPreview(false);
    this.evalPanel.start();
    this.ready = true;
    // Time spent tracing: counted while the page is visible and the user active in the last minute.
    this.timers.push(
      window.setInterval(() => {
        if (document.visibilityState === "visible" && performance.now() - this.lastInput < 60000) {
          this.seconds++;
          this.unsentSeconds++;
          this.updateStatus();
        }
      }, 1000),
      window.setInterval(() => void this.flushTime(), 20000),
    );
    api.addTime(this.cell.id, 0).then((r) => {
      this.seconds = Math.max(this.seconds, r.total_seconds ?? 0);
      this.updateStatus();
    }, () => {});
    const ro = new ResizeObserver(() => AXES.forEach((a) => this.views[a].requestPaint()));
    AXES.forEach((a) => ro.observe(this.views[a].canvas));
    this.ro = ro;
  }
  private ro: ResizeObserver | null = null;

  /** Stop timers and listeners (when leaving the screen). */
  dispose(): void {
    if (this.disposed) return;
    this.disposed = true;
    document.removeEventListener("keydown", this.keyHandler);
    this.timers.forEach((t) => clearInterval(t));
    this.ro?.disconnect();
    void this.flushTime(true);
    this.viewer?.dispose();
    this.saveState();
  }

  private async flushTime(keepalive = false): Promise<void> {
    const s = this.unsentSeconds;
    if (s <= 0) return;
    this.unsentSeconds = 0;
    try {
      if (keepalive) {
        await fetch(`/api/cells/${encodeURIComponent(this.cell.id)}/time`, { method: "POST", keepalive: true, headers: { "Content-Type": "application/json" }, body: JSON.stringify({ seconds: s }), credentials: "same-origin" });
      } else {
        const r = await this.host.api.addTime(this.cell.id, s);
        if (typeof r?.total_seconds === "number") this.seconds = Math.max(this.seconds, r.total_seconds);
      }
    } catch {
      this.unsentSeconds += s;
    }
  }

  private fillLabels(): void {
    const sel = this.el.label as HTMLSelectElement;
    clear(sel);
    this.labels.forEach((l, n) => sel.append(h("option", { value: String(l.id) }, `${n < 9 ? n + 1 + " · " : ""}${l.name}`)));
    sel.value = String(this.st.label);
    (this.el.swatch as HTMLElement).style.background = this.labelOf(this.st.label).color;
  }

  private fillMethods(): void {
    const sel = this.el.method as HTMLSelectElement;
    clear(sel);
    if (this.methods.length === 0) sel.append(h("option", { value: "" }, "default"));
    this.methods.forEach((m, n) => sel.append(h("option", { value: m.name, title: m.description }, n === 0 ? `${m.name} (default)` : m.name)));
    if (!this.methods.some((m) => m.name === this.st.method)) this.st.method = this.methods[0]?.name ?? "";
    sel.value = this.st.method;
  }

  private syncControls(): void {
    (this.el.axis as HTMLSelectElement).value = this.st.axis;
    const si = this.el.sliceIndex as HTMLInputElement;
    si.max = String(this.depth - 1);
    si.value = String(this.index);
    this.el.sliceMax.textContent = `/ ${this.depth - 1}`;
    (this.el.skip as HTMLInputElement).value = String(this.st.skip);
    (this.el.label as HTMLSelectElement).value = String(this.st.label);
    (this.el.swatch as HTMLElement).style.background = this.labelOf(this.st.label).color;
    (this.el.wlo as HTMLInputElement).value = windowText(this.win.lo, this.cell.dtype);
    (this.el.whi as HTMLInputElement).value = windowText(this.win.hi, this.cell.dtype);
    (this.el.preset as HTMLSelectElement).value = this.st.preset === "manual" ? "manual" : this.currentPreset().id;
  }

  /** Put the working view in the big slot, the others beside it. */
  private placeViews(): void {
    const others = AXES.filter((a) => a !== this.st.axis);
    this.el.main.replaceChildren(this.views[this.st.axis].canvas);
    this.el.sideA.replaceChildren(this.views[others[0]].canvas);
    this.el.sideB.replaceChildren(this.views[others[1]].canvas);
    AXES.forEach((a) => this.views[a].fit());
  }

  // ---------- window/level ----------

  private applyWindow(repaint = true): void {
    this.win = applyBrightnessContrast(this.baseWin, this.st.brightness, this.st.contrast);
    this.setLut();
    if (repaint) this.syncControls();
    this.saveState();
    if (repaint) this.paintAll();
  }

  private setLut(): void {
    this.lut = buildLut(this.cell.dtype, this.win);
    this.lutVersion++;
  }

  private fillPresets(): void {
    const sel = this.el.preset as HTMLSelectElement;
    clear(sel);
    for (const p of this.presets) {
      const lw = p.level !== undefined ? ` (L ${p.level} / W ${p.width})` : "";
      sel.append(h("option", { value: p.id }, p.name + lw));
    }
    sel.append(h("option", { value: "manual", disabled: true }, "Manual"));
  }

  /** The preset in force: the chosen one when this cell offers it, else the cell's default. */
  private currentPreset(): Preset {
    return this.presets.find((p) => p.id === this.st.preset) ?? defaultPreset(this.hist, this.cell.dtype);
  }

  /** The base window of the view settings: the manual one, or the preset's. */
  private baseWindow(): Window {
    if (this.st.preset === "manual" && this.st.manual) return this.st.manual;
    return presetWindow(this.currentPreset(), this.hist, this.cell);
  }

  /** Set the base window and reset brightness and contrast. */
  private setBase(w: Window): void {
    this.baseWin = w;
    this.st.brightness = 0;
    this.st.contrast = 0;
    (this.el.bright as HTMLInputElement).value = "0";
    (this.el.contrast as HTMLInputElement).value = "0";
    this.applyWindow();
  }

  private choosePreset(id: string): void {
    const p = this.presets.find((q) => q.id === id);
    if (!p) return;
    this.st.preset = p.id;
    this.st.manual = null;
    this.setBase(presetWindow(p, this.hist, this.cell));
  }

  private manualWindow(): void {
    const lo = Number((this.el.wlo as HTMLInputElement).value);
    const hi = Number((this.el.whi as HTMLInputElement).value);
    if (!(Number.isFinite(lo) && Number.isFinite(hi) && hi > lo)) return;
    this.st.preset = "manual";
    this.st.manual = { lo, hi };
    this.setBase({ lo, hi });
  }

  private autoWin(): void {
    this.choosePreset(AUTO_PRESET.id);
  }

  // ---------- slices ----------

  private async loadSlice(axis: Axis, index: number): Promise<SliceImage> {
    const key = `${axis}/${index}`;
    const hit = this.cache.get(key);
    if (hit) {
      this.cache.delete(key);
      this.cache.set(key, hit); // LRU order
      if (hit.lutVersion !== this.lutVersion) this.repaintBitmap(hit);
      return hit;
    }
    let p = this.inflight.get(key);
    if (!p) {
      p = this.host.api.slice(this.cell.id, axis, index).then((r) => {
        const raw = decodeSlice(r.data, r.dtype, r.width, r.height);
        const bitmap = document.createElement("canvas");
        bitmap.width = r.width;
        bitmap.height = r.height;
        const img: SliceImage = { width: r.width, height: r.height, raw, bitmap, lutVersion: -1 };
        this.repaintBitmap(img);
        this.cache.set(key, img);
        while (this.cache.size > 160) this.cache.delete(this.cache.keys().next().value as string);
        return img;
      });
      this.inflight.set(key, p);
      p.finally(() => this.inflight.delete(key)).catch(() => {});
    }
    return p;
  }

  private repaintBitmap(img: SliceImage): void {
    const ctx = img.bitmap.getContext("2d");
    if (!ctx) return;
    const data = ctx.createImageData(img.width, img.height);
    renderGrey(img.raw, this.lut, data.data);
    ctx.putImageData(data, 0, 0);
    img.lutVersion = this.lutVersion;
  }

  /** Load the three views' slices and paint. */
  private async refreshAll(): Promise<void> {
    await Promise.all(AXES.map((a) => this.refreshView(a)));
    this.updateStatus();
  }

  private async refreshView(a: Axis): Promise<void> {
    const idx = this.st.focus[axisDim(a)];
    const v = this.views[a];
    v.index = idx;
    try {
      const img = await this.loadSlice(a, idx);
      if (v.index !== idx) return; // a newer request won
      v.image = img;
    } catch (e) {
      this.host.toast(`slice ${a}=${idx}: ${(e as Error).message}`, true);
    }
    this.paintView(a);
  }

  private paintAll(): void {
    for (const a of AXES) {
      const img = this.views[a].image;
      if (img && img.lutVersion !== this.lutVersion) this.repaintBitmap(img);
      this.paintView(a);
    }
  }

  /** Build a view's scene and paint it at the next frame. */
  private paintView(a: Axis): void {
    const v = this.views[a];
    const working = a === this.st.axis;
    const f = this.st.focus;
    const [du, dv] = inPlane(a);
    v.scene.working = working;
    v.scene.cross = { u: f[du] + 0.5, v: f[dv] + 0.5, colorU: AXIS_COLOR[AXES[du]], colorV: AXIS_COLOR[AXES[dv]] };
    const idx = f[axisDim(a)];
    v.scene.caption = `${a.toUpperCase()} = ${idx}${working ? "  · working view" : ""}`;
    v.scene.captionColor = AXIS_COLOR[a];
    v.scene.overlay = this.evalPanel.overlayFor(a, idx);
    if (working) {
      const cs: PaintContour[] = [];
      for (const c of this.contours) {
        if (c.axis !== a || c.index !== idx) continue;
        const cur = c.label === this.st.label;
        cs.push({ points: c.points, color: cur ? FINISHED : this.labelOf(c.label).color, width: cur ? 2 : 1.5 });
      }
      for (const [key, res] of this.previews) {
        if (res.axis !== a) continue;
        const s = res.slices.find((x) => x.index === idx);
        if (!s || s.drawn) continue;
        const label = Number(key.split("/")[0]);
        if (label === this.st.label && this.drawn.has(idx)) continue;
        for (const p of s.contours) cs.push({ points: p, color: this.labelOf(label).color, width: label === this.st.label ? 2 : 1.2, dashed: true });
      }
      v.scene.contours = cs;
      v.scene.rects = [];
      v.scene.stroke = this.recorder.pending ? this.recorder.current : null;
    } else {
      v.scene.contours = [];
      v.scene.stroke = null;
      v.scene.rects = this.cutRects(a);
    }
    v.requestPaint();
  }

  /**
   * Where the working axis' contours (drawn and interpolated) cut the plane of
   * view `b`: one thin strip per working slice, filled in the label colour.
   */
  private cutRects(b: Axis): PaintRect[] {
    const A = this.st.axis;
    const [au, av] = inPlane(A);
    const [bu] = inPlane(b);
    const db = axisDim(b);
    const at = this.st.focus[db] + 0.5;
    // Along which in-plane dim of A the cut runs.
    const swap = db === au; // b fixes A's u: scan the polygons with u and v exchanged
    const alongDim = swap ? av : au;
    const rects: PaintRect[] = [];
    const bySlice = new Map<string, { label: number; index: number; polys: Vec2[][]; drawn: boolean }>();
    for (const c of this.contours) {
      if (c.axis !== A) continue;
      const k = `${c.label}/${c.index}`;
      const e = bySlice.get(k) ?? { label: c.label, index: c.index, polys: [], drawn: true };
      e.polys.push(c.points);
      bySlice.set(k, e);
    }
    for (const [key, res] of this.previews) {
      if (res.axis !== A) continue;
      const label = Number(key.split("/")[0]);
      for (const s of res.slices) {
        if (s.drawn || bySlice.has(`${label}/${s.index}`)) continue;
        bySlice.set(`${label}/${s.index}`, { label, index: s.index, polys: s.contours, drawn: false });
      }
    }
    for (const e of bySlice.values()) {
      const polys = swap ? e.polys.map((p) => p.map(([x, y]) => [y, x] as Vec2)) : e.polys;
      const color = this.labelOf(e.label).color + (e.drawn ? "cc" : "66");
      for (const [s0, s1] of scanlineIntervals(polys, at)) {
        // In view b, `alongDim` and A's dim are its u and v in some order.
        if (alongDim === bu) rects.push({ r: [s0, e.index, s1, e.index + 1], color });
        else rects.push({ r: [e.index, s0, e.index + 1, s1], color });
      }
    }
    return rects;
  }

  // ---------- navigation ----------

  /** Go to slice `index` of the working axis (clamped). */
  async goto(index: number): Promise<void> {
    if (!Number.isFinite(index)) return;
    const i = Math.min(this.depth - 1, Math.max(0, Math.round(index)));
    if (this.recorder.pending) this.recorder.cancel();
    const t0 = performance.now();
    this.st.focus[axisDim(this.st.axis)] = i;
    this.saveState();
    this.syncControls();
    await this.refreshView(this.st.axis);
    // The slice's picture is painted at the next frame: measure to it.
    await new Promise((r) => requestAnimationFrame(() => r(null)));
    this.figures.sliceSwitch.push(performance.now() - t0);
    AXES.filter((a) => a !== this.st.axis).forEach((a) => this.paintView(a));
    this.updateStatus();
    this.prefetch();
  }

  private prefetch(): void {
    const a = this.st.axis;
    for (const d of [this.st.skip, -this.st.skip, 1, -1]) {
      const j = this.index + d;
      if (j >= 0 && j < this.depth) void this.loadSlice(a, j).catch(() => {});
    }
  }

  /** Move by `n` slices. */
  step(n: number): void {
    void this.goto(this.index + n);
  }

  /** Trace on another axis. */
  setAxis(a: Axis): void {
    if (a === this.st.axis) return;
    this.recorder.cancel();
    this.st.axis = a;
    this.saveState();
    this.placeViews();
    this.syncControls();
    void this.reloadDrawn().then(() => {
      this.paintAll();
      if (this.hasDrawn() && !this.previews.has(`${this.st.label}/${a}`)) void this.runPreview(false);
    });
    void this.refreshAll();
  }

  /** Choose the component being traced. */
  setLabel(id: number): void {
    if (!this.labels.some((l) => l.id === id)) return;
    this.recorder.cancel();
    this.st.label = id;
    this.saveState();
    this.syncControls();
    void this.reloadDrawn().then(() => {
      this.paintAll();
      this.updateStatus();
      if (this.hasDrawn() && !this.previews.has(`${id}/${this.st.axis}`)) void this.runPreview(false);
    });
    this.paintAll();
  }

  private pick(v: SliceView, u: number, vv: number): void {
    const [du, dv] = inPlane(v.axis);
    const [w, hh] = v.size;
    const px = pixelAt(u, vv, w, hh);
    if (!px) return;
    this.st.focus[du] = px[0];
    this.st.focus[dv] = px[1];
    this.saveState();
    this.syncControls();
    this.recorder.cancel();
    void this.refreshAll();
  }

  private async addLabel(input: HTMLInputElement): Promise<void> {
    const name = input.value.trim();
    if (!name) return;
    try {
      const l = await this.host.api.addLabel(name);
      this.labels.push(l);
      input.value = "";
      this.fillLabels();
      this.setLabel(l.id);
    } catch (e) {
      this.host.toast(`could not add the component: ${(e as Error).message}`, true);
    }
  }

  private async setDone(done: boolean): Promise<void> {
    try {
      await this.host.api.setStatus(this.cell.id, done ? "done" : "in_progress");
      this.cell.status = done ? "done" : "in_progress";
    } catch (e) {
      this.host.toast((e as Error).message, true);
    }
  }

  private async nextCell(): Promise<void> {
    this.addContour();
    try {
      await this.host.outbox.flush();
      const cells = await this.host.api.cells(true);
      const others = cells.filter((c) => c.id !== this.cell.id);
      if (others.length === 0) {
        this.host.toast("no other cell in your queue");
        return;
      }
      const all = await this.host.api.cells(false);
      const order = all.map((c) => c.id);
      const here = order.indexOf(this.cell.id);
      const next = others.map((c) => ({ c, d: (order.indexOf(c.id) - here + order.length) % order.length })).sort((a, b) => a.d - b.d)[0].c;
      this.host.openCell(next.id);
    } catch (e) {
      this.host.toast(`next cell: ${(e as Error).message}`, true);
    }
  }

  // ---------- drawing ----------

  private penDown(v: SliceView, s: Sample, tool: string): void {
    this.lastInput = performance.now();
    if (v.axis !== this.st.axis) return;
    // Closing feels the same at every zoom: 10 screen pixels.
    this.recorder.closeTol = 10 / (v.t?.scale ?? 1);
    this.recorder.penDown(s, tool);
    this.paintView(v.axis);
  }

  private penMove(v: SliceView, s: Sample[], t: number): void {
    this.lastInput = performance.now();
    this.recorder.penMove(s);
    this.moveEventTimes.push(t);
    this.paintView(v.axis);
  }

  private penUp(v: SliceView, s: Sample | undefined): void {
    const r = this.recorder.penUp(s);
    if (r.kind === "closed") this.commit(r.contour);
    this.paintView(v.axis);
  }

  /** *Add contour*: finish the red contour (closing it) and save it. */
  addContour(): void {
    const c = this.recorder.finish();
    if (c) this.commit(c);
    this.paintView(this.st.axis);
  }

  private commit(c: FinishedContour): void {
    const cell = this.cell.id;
    const body = { label: this.st.label, axis: this.st.axis, index: this.index, points: c.points.map(([u, v]) => [round3(u), round3(v)] as Vec2), pressure: c.pressure, times_ms: c.times_ms, tool: c.tool };
    this.previewT0 = performance.now();
    this.drawn.set(this.index, false);
    const client_id = newClientId();
    this.committedAt.set(client_id, performance.now());
    void this.host.outbox.push({ kind: "contour", cell, client_id, body });
    this.recompute();
    if (this.cell.status === "not_started") void this.setDone(false);
  }

  /** Clear this label's contours on the slice (undoable). */
  clearContours(): void {
    this.recorder.cancel();
    this.previewT0 = performance.now();
    this.drawn.delete(this.index);
    void this.host.outbox.push({ kind: "replace", cell: this.cell.id, client_id: newClientId(), axis: this.st.axis, index: this.index, label: this.st.label, contours: [] });
    this.recompute();
  }

  /** The component is absent on this slice. */
  markEmpty(): void {
    this.recorder.cancel();
    this.previewT0 = performance.now();
    this.drawn.set(this.index, true);
    void this.host.outbox.push({ kind: "empty", cell: this.cell.id, client_id: newClientId(), axis: this.st.axis, index: this.index, label: this.st.label });
    this.recompute();
  }

  private async undoRedo(which: "undo" | "redo"): Promise<void> {
    this.recorder.cancel();
    try {
      await this.host.outbox.flush();
      if (this.host.outbox.pending.length) {
        this.host.toast("not connected: undo waits until the changes are saved", true);
        return;
      }
      const r = which === "undo" ? await this.host.api.undo(this.cell.id) : await this.host.api.redo(this.cell.id);
      if (!r.changed) {
        this.host.toast(which === "undo" ? "nothing to undo" : "nothing to redo");
        return;
      }
      this.previewT0 = performance.now();
      await this.reloadContours();
      this.paintAll();
      this.updateStatus();
      this.schedulePreview();
    } catch (e) {
      this.host.toast(`${which}: ${(e as Error).message}`, true);
    }
  }

  /** Called by the app when the outbox acknowledged an operation of this cell. */
  onSent(op: import("./queue").Op, answer: unknown): void {
    if (op.cell !== this.cell.id) return;
    const t0 = this.committedAt.get(op.client_id);
    if (t0 !== undefined) {
      this.figures.saveLatency.push(performance.now() - t0);
      this.committedAt.delete(op.client_id);
    }
    if (op.kind === "contour" && answer && typeof answer === "object" && "id" in answer) {
      const c = answer as Contour;
      if (!this.serverContours.some((x) => x.id === c.id)) this.serverContours.push(c);
      this.recompute();
    } else {
      void this.reloadContours().then(() => this.paintAll());
    }
    const label = op.kind === "contour" ? op.body.label : op.label;
    const axis = op.kind === "contour" ? op.body.axis : op.axis;
    if (label === this.st.label && axis === this.st.axis && this.host.outbox.pending.length === 0) this.schedulePreview();
  }

  /** Called when the outbox changed. */
  onQueue(n: number, err?: string): void {
    const u = this.el.unsaved;
    if (!u) return;
    u.textContent = n > 0 ? `${n} change${n > 1 ? "s" : ""} not saved yet${err ? ` (${err}) — retrying` : ""}` : "all changes saved";
    u.className = n > 0 ? "unsaved warn" : "unsaved ok";
    if (n > 0 || err) this.recompute();
  }

  private recompute(): void {
    this.contours = applyPending(this.serverContours, this.host.outbox.pending as import("./queue").Op[], this.cell.id);
    this.paintAll();
    this.updateStatus();
  }

  private async reloadContours(): Promise<void> {
    try {
      this.serverContours = await this.host.api.contours(this.cell.id);
    } catch (e) {
      if (!(e instanceof ApiError)) this.host.toast("offline: showing unsaved contours only", true);
    }
    await this.reloadDrawn();
    this.contours = applyPending(this.serverContours, this.host.outbox.pending as import("./queue").Op[], this.cell.id);
  }

  private async reloadDrawn(): Promise<void> {
    const m = new Map<number, boolean>();
    try {
      for (const d of await this.host.api.drawn(this.cell.id, this.st.label, this.st.axis)) m.set(d.index, d.empty);
    } catch {
      for (const c of this.serverContours) if (c.label === this.st.label && c.axis === this.st.axis) m.set(c.index, false);
    }
    for (const op of this.host.outbox.pending) {
      if (op.cell !== this.cell.id) continue;
      if (op.kind === "contour" && op.body.label === this.st.label && op.body.axis === this.st.axis) m.set(op.body.index, false);
      if (op.kind === "empty" && op.label === this.st.label && op.axis === this.st.axis) m.set(op.index, true);
      if (op.kind === "replace" && op.label === this.st.label && op.axis === this.st.axis) m.delete(op.index);
    }
    this.drawn = m;
  }

  private hasDrawn(): boolean {
    return this.drawn.size > 0;
  }

  // ---------- interpolation ----------

  private schedulePreview(): void {
    if (!(this.el.autoPreview as HTMLInputElement).checked) return;
    void this.runPreview(false);
  }

  /** Interpolate the current label along the working axis and show it dashed. */
  async runPreview(explicit: boolean): Promise<void> {
    if (this.previewBusy) {
      this.previewAgain = true;
      return;
    }
    this.previewBusy = true;
    const label = this.st.label;
    const axis = this.st.axis;
    const t0 = this.previewT0;
    try {
      if (explicit) await this.host.outbox.flush();
      await this.reloadDrawn();
      const contoursDrawn = [...this.drawn.values()].filter((empty) => !empty).length;
      if (contoursDrawn === 0) {
        this.previews.delete(`${label}/${axis}`);
        this.el.volume.textContent = "";
        if (explicit) this.host.toast("draw at least one contour first");
      } else {
        const r = await this.host.api.interpolate(this.cell.id, label, axis, this.st.method || undefined);
        this.previews.set(`${label}/${axis}`, r);
        this.el.volume.textContent = `${this.labelOf(label).name}: ${fmtNum(r.volume)} ${r.unit} (${r.method})`;
        this.paintAll();
        if (t0 !== null) {
          await new Promise((res) => requestAnimationFrame(() => res(null)));
          this.figures.previewLatency.push(performance.now() - t0);
          if (this.previewT0 === t0) this.previewT0 = null;
        }
        if (this.show3d) void this.update3d();
      }
    } catch (e) {
      if (explicit) this.host.toast(`interpolation: ${(e as Error).message}`, true);
      else this.el.volume.textContent = `preview: ${(e as Error).message}`;
    } finally {
      this.previewBusy = false;
      this.updateStatus();
    }
    if (this.previewAgain) {
      this.previewAgain = false;
      void this.runPreview(false);
    }
  }

  /** Show or hide the 3D view. */
  async toggle3d(on = !this.show3d): Promise<void> {
    this.show3d = on;
    this.el.v3d.classList.toggle("on", on);
    if (!on) {
      this.viewer?.dispose();
      this.viewer = null;
      this.el.v3dMsg.textContent = "3D view — click to show the interpolated surfaces (D)";
      this.el.v3dMsg.hidden = false;
      return;
    }
    await this.update3d();
  }

  private async update3d(): Promise<void> {
    this.el.v3dMsg.hidden = false;
    this.el.v3dMsg.textContent = "computing surfaces…";
    try {
      const { Viewer3D } = await import("./view3d");
      if (!this.viewer) this.viewer = new Viewer3D(this.el.v3dHost);
      // Every component with contours on the working axis, outer (lower label) first.
      const labels = [...new Set(this.contours.filter((c) => c.axis === this.st.axis).map((c) => c.label))].sort((a, b) => a - b);
      const surfaces = [];
      for (const l of labels) {
        let res = this.previews.get(`${l}/${this.st.axis}`);
        if (!res) {
          res = await this.host.api.interpolate(this.cell.id, l, this.st.axis, this.st.method || undefined);
          this.previews.set(`${l}/${this.st.axis}`, res);
        }
        const mesh = await this.host.api.mesh(this.cell.id, res.result_id);
        surfaces.push({ name: this.labelOf(l).name, color: this.labelOf(l).color, mesh });
      }
      if (!this.show3d) return;
      this.viewer.show(surfaces);
      this.el.v3dMsg.textContent = surfaces.length ? surfaces.map((s) => s.name).join(" · ") : "nothing traced yet";
      this.paintAll();
    } catch (e) {
      this.el.v3dMsg.textContent = `3D: ${(e as Error).message}`;
    }
  }

  private refreshOverlays(): void {
    this.paintAll();
  }

  // ---------- status & keys ----------

  private updateStatus(): void {
    const s = this.el.status;
    if (!s) return;
    const a = this.st.axis;
    const idx = this.index;
    let where = "—";
    let value = "—";
    if (this.cursor) {
      const v = this.views[this.cursor.axis];
      const px = pixelAt(this.cursor.u, this.cursor.v, v.size[0], v.size[1]);
      if (px) {
        const [i, j, k] = voxelOf(this.cursor.axis, v.index, px[0], px[1]);
        where = `(${i}, ${j}, ${k})`;
        if (v.image) value = formatValue(v.image.raw[px[0] + v.image.width * px[1]], this.cell.dtype);
      }
    }
    const d = this.drawn.get(idx);
    const pv = this.previews.get(`${this.st.label}/${a}`);
    const kind = d === undefined ? (pv ? "interpolated" : "not drawn") : d ? "drawn (empty)" : "drawn";
    const nDrawn = this.drawn.size;
    s.replaceChildren(
      h("span", {}, `axis ${a}`),
      h("span", { testid: "status-slice" }, `slice ${idx} / ${this.depth - 1}`),
      h("span", { testid: "status-voxel" }, `voxel ${where}`),
      h("span", { testid: "status-value" }, `value ${value}`),
      h("span", {}, h("i", { class: "swatch", style: { background: this.labelOf(this.st.label).color } }), ` ${this.labelOf(this.st.label).name}`),
      h("span", { testid: "status-kind", class: kind.startsWith("drawn") ? "ok" : "" }, `${kind} · ${nDrawn} drawn`),
      h("span", { title: "time spent tracing this cell" }, `time ${hms(this.seconds)}`),
      h("span", { class: "grow" }),
      h("button", { class: "link", onclick: () => (this.el.help.hidden = false), title: "Keyboard shortcuts (?)" }, "? help"),
    );
  }

  private onKey(e: KeyboardEvent): void {
    const t = e.target as HTMLElement | null;
    if (t && (t.tagName === "INPUT" || t.tagName === "TEXTAREA" || t.tagName === "SELECT") && !(e.key === "Escape")) return;
    const act = actionOf(e);
    if (!act) return;
    e.preventDefault();
    this.lastInput = performance.now();
    this.doAction(act);
  }

  /** Run a shortcut action. */
  doAction(act: Action): void {
    switch (act) {
      case "next-slice":
        return this.step(this.st.skip);
      case "prev-slice":
        return this.step(-this.st.skip);
      case "next-slice-1":
        return this.step(1);
      case "prev-slice-1":
        return this.step(-1);
      case "add-contour":
        return this.addContour();
      case "cancel-stroke":
        this.el.help.hidden = true;
        this.recorder.cancel();
        return this.paintView(this.st.axis);
      case "clear-contours":
        return this.clearContours();
      case "mark-empty":
        return this.markEmpty();
      case "undo":
      case "redo":
        void this.undoRedo(act);
        return;
      case "interpolate":
        void this.runPreview(true);
        return;
      case "axis-x":
      case "axis-y":
      case "axis-z":
        return this.setAxis(act.slice(5) as Axis);
      case "zoom-in":
        return this.views[this.st.axis].zoom(1.25);
      case "zoom-out":
        return this.views[this.st.axis].zoom(0.8);
      case "zoom-fit":
        return AXES.forEach((a) => this.views[a].fit());
      case "auto-window":
        return this.autoWin();
      case "next-cell":
        void this.nextCell();
        return;
      case "toggle-3d":
        void this.toggle3d();
        return;
      case "toggle-overlay":
        return this.evalPanel.toggleOverlay();
      case "help":
        this.el.help.hidden = !this.el.help.hidden;
        return;
      default: {
        const n = Number(act.slice(6));
        const l = this.labels[n - 1];
        if (l) this.setLabel(l.id);
      }
    }
  }

  // ---------- test hooks ----------

  /** Slice -> client coordinates of a view (for the end-to-end test). */
  sliceToClient(a: Axis, u: number, v: number): Vec2 {
    return this.views[a].sliceToClient(u, v);
  }

  /** Width and height of view `a`'s slices, and the slice it shows. */
  sliceSize(a: Axis): [number, number, number] {
    const v = this.views[a];
    return [v.size[0], v.size[1], v.index];
  }

  /** Resolves when every change is saved and no preview is running. */
  async idle(): Promise<void> {
    await this.host.outbox.flush();
    for (let n = 0; n < 600 && (this.previewBusy || this.previewAgain || this.host.outbox.pending.length); n++) await new Promise((r) => setTimeout(r, 25));
  }

  /** A summary of the state (for the end-to-end test). */
  summary(): { axis: Axis; index: number; label: number; drawn: number[]; empty: number[]; contours: number; onSlice: number; preview: boolean; overlay: boolean; pending: number } {
    const mine = this.contours.filter((c) => c.label === this.st.label && c.axis === this.st.axis);
    return {
      axis: this.st.axis,
      index: this.index,
      label: this.st.label,
      drawn: [...this.drawn.keys()].sort((a, b) => a - b),
      empty: [...this.drawn].filter(([, e]) => e).map(([i]) => i).sort((a, b) => a - b),
      contours: mine.length,
      onSlice: mine.filter((c) => c.index === this.index).length,
      preview: this.previews.has(`${this.st.label}/${this.st.axis}`),
      overlay: this.views[this.st.axis].scene.overlay !== null,
      pending: this.host.outbox.pending.length,
    };
  }
}

function round3(x: number): number {
  return Math.round(x * 1000) / 1000;
}

function fmtNum(x: number): string {
  if (!Number.isFinite(x)) return String(x);
  return x >= 1000 ? x.toFixed(0) : x.toPrecision(4);
}
