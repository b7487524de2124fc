/**
 * The tracing screen of one cell: three linked orthogonal views, the tools
 * of the original program (skip, add contour, clear, mark empty, undo/redo,
 * next cell) and what goes beyond it (live interpolation preview, 3D view,
 * status line, shortcuts, offline-safe saving, evaluation panel).
 *
 * This class wires the parts together and owns navigation and drawing; the
 * parts each do one job: `layout` (the page and its elements), `viewstate`
 * (settings kept per cell), `display` (window/level), `slicecache` (decoded
 * slices), `reconcile` (server contours + the outbox's pending changes),
 * `preview` (interpolation runs), `scenes` (what the views paint),
 * `timetrack` (time spent) and `panel3d` (the 3D view).
 */
import type { Api, CellDetail, InterpResult, Label, Me, Method } from "./api";
import { DisplayWindow } from "./display";
import { EvalPanel } from "./evalpanel";
import { buildLayout, fillLabels, fillMethods, fillPresets, type TracerElements } from "./layout";
import { Panel3D } from "./panel3d";
import { Previews, exportMethod, methodNote } from "./preview";
import { SummaryPanel } from "./summary";
import { Pen } from "./pen";
import { newClientId, type Op, type Outbox } from "./queue";
import { ChangesPending, Tracings, type Target } from "./reconcile";
import { cutRects, uncertainTints, workingContours, type Traced } from "./scenes";
import { actionOf, type Action } from "./shortcuts";
import { statusLine } from "./statusline";
import { Advisor, loadDoneWhen, renderAdvice, saveDoneWhen } from "./advice";
import type { SliceView } from "./sliceview";
import type { FinishedContour } from "./stroke";
import { TimeTracker } from "./timetrack";
import { axisDim, inPlane, pixelAt, voxelOf, type Axis, type Vec2 } from "./transform";
import type { Surface } from "./view3d";
import { LinkedViews, type Overlay } from "./views";
import { AXES, loadViewState, saveViewState, type ViewState } from "./viewstate";
import { formatValue, windowText } from "./windowing";

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
  private views: LinkedViews;
  private st: ViewState;
  private display: DisplayWindow;
  private tracings: Tracings;
  private previews: Previews;
  private advisor: Advisor;
  /** The method in use the advice and the summary were last asked for. */
  private methodAsked = "";
  private doneWhen = loadDoneWhen(localStorage);
  private tracingSummary: SummaryPanel;
  private time: TimeTracker;
  private panel3d: Panel3D;
  private pen: Pen;
  private methods: Method[] = [];
  private labels: Label[];
  private cursor: { axis: Axis; u: number; v: number } | null = null;
  private evalPanel: EvalPanel;
  private disposed = false;
  private el: TracerElements;
  private keyHandler = (e: KeyboardEvent) => this.onKey(e);

  constructor(
    private host: TracerHost,
    readonly cell: CellDetail,
  ) {
    const api = host.api;
    this.labels = cell.labels.length ? cell.labels : [{ id: 1, name: "Cell", color: "#e6194b" }];
    this.st = loadViewState(localStorage, cell.id, cell.dims, this.labels);
    this.display = new DisplayWindow(cell, this.st);
    this.tracings = new Tracings(api, host.outbox, cell.id, (msg) => host.toast(msg, true));
    this.time = new TimeTracker(api, cell.id, () => this.updateStatus());
    this.previews = new Previews(api, cell.id, {
      live: () => this.el.autoPreview.checked,
      target: () => ({
        label: this.st.label,
        axis: this.st.axis,
        method: this.st.method,
        confidence: this.st.uncertainty,
      }),
      prepare: async (explicit) => {
        if (explicit) await host.outbox.flush();
        await this.tracings.reloadDrawn(this.target);
        return [...this.tracings.drawn.values()].filter((empty) => !empty).length;
      },
      show: (label, r, explicit) => this.showPreview(label, r, explicit),
      updated: () => {
        if (this.panel3d.on) void this.panel3d.update();
      },
      failed: (msg, explicit) => {
        if (explicit) host.toast(`interpolation: ${msg}`, true);
        else this.el.volume.textContent = `preview: ${msg}`;
      },
      latency: (ms) => this.figures.previewLatency.push(ms),
      settled: () => this.updateStatus(),
    });
    this.advisor = new Advisor(api, cell.id, {
      target: () => ({ label: this.st.label, axis: this.st.axis, method: this.methodInUse }),
      show: (state) => renderAdvice(this.el, state, this.doneWhen),
    });
    this.pen = new Pen({
      workingAxis: () => this.st.axis,
      paint: (a) => this.paintView(a),
      commit: (c) => this.commit(c),
      touch: () => this.time.touch(),
      latency: (ms) => this.figures.strokeLatency.push(ms),
    });
    this.views = new LinkedViews(cell, (axis, index) => api.slice(cell.id, axis, index), {
      handlers: {
        penDown: (v, s, tool) => this.pen.penDown(v, s, tool),
        penMove: (v, s, t) => this.pen.penMove(v, s, t),
        penUp: (v, s) => this.pen.penUp(v, s),
        pick: (v, u, vv) => this.pick(v, u, vv),
        hover: (v, u, vv, inside) => {
          this.cursor = inside ? { axis: v.axis, u, v: vv } : null;
          this.updateStatus();
        },
        changed: () => {},
      },
      focus: () => this.st,
      overlay: (a, idx, working) => this.overlay(a, idx, working),
      painted: (now) => this.pen.painted(now),
      failed: (msg) => host.toast(msg, true),
    });
    this.evalPanel = new EvalPanel({
      api,
      me: host.me,
      cell,
      label: () => this.st.label,
      labels: () => this.labels,
      overlayChanged: () => this.paintAll(),
      toast: (msg, error) => host.toast(msg, error),
    });
    this.el = this.buildPage();
    this.root = this.el.root;
    this.tracingSummary = new SummaryPanel(
      api,
      cell.id,
      () => this.st.label,
      () => this.methodInUse,
      this.el.summary,
    );
    this.panel3d = new Panel3D(
      this.el,
      () => this.surfaces(),
      () => this.paintAll(),
    );
  }

  private buildPage(): TracerElements {
    return buildLayout(
      {
        dims: this.cell.dims,
        brightness: this.st.brightness,
        contrast: this.st.contrast,
        done: this.cell.status === "done",
        exports: ["nii.gz", "nrrd", "seg.nrrd", "tiff", "contours"].map((f) => [
          f,
          () => this.host.api.exportUrl(this.cell.id, f, exportMethod(this.st.method)),
        ]),
        evalPanel: this.evalPanel.root,
        doneWhen: this.doneWhen,
        uncertainty: this.st.uncertainty,
      },
      {
        run: (action) => this.doAction(action),
        setAxis: (a) => this.setAxis(a),
        goto: (i) => void this.goto(i),
        setSkip: (n) => {
          this.st.skip = Math.max(1, Math.round(n || 1));
          this.saveState();
          return this.st.skip;
        },
        setLabel: (id) => this.setLabel(id),
        addLabel: () => void this.addLabel(),
        setMethod: (name) => {
          this.st.method = name;
          this.saveState();
          this.showMethodNote();
          this.previews.schedule();
          this.methodMayHaveChanged();
        },
        setUncertainty: (on) => this.setUncertainty(on),
        setBrightness: (v) => {
          this.st.brightness = v;
          this.applyWindow();
        },
        setContrast: (v) => {
          this.st.contrast = v;
          this.applyWindow();
        },
        choosePreset: (id) => this.choosePreset(id),
        manualWindow: () => {
          if (this.display.setManual(Number(this.el.wlo.value), Number(this.el.whi.value))) this.baseChanged();
        },
        setDone: (done) => void this.setDone(done),
        showList: () => this.host.showList(),
        show3d: () => {
          if (!this.panel3d.on) void this.toggle3d(true);
        },
        setDoneWhen: (v) => {
          this.doneWhen = v;
          saveDoneWhen(localStorage, v);
          renderAdvice(this.el, this.advisor.current, v);
        },
      },
    );
  }

  // ---------- state ----------

  private saveState(): void {
    saveViewState(localStorage, this.cell.id, this.st);
  }

  /**
   * The method the label is interpolated with: the one picked, else the one
   * the last preview's leave-one-out recommended ("" before any: the default).
   */
  private get methodInUse(): string {
    return this.st.method || (this.previews.get(this.st.label, this.st.axis)?.recommended_method ?? "");
  }

  private get index(): number {
    return this.st.focus[axisDim(this.st.axis)];
  }

  private get depth(): number {
    return this.cell.dims[axisDim(this.st.axis)];
  }

  /** The label and axis being traced. */
  private get target(): Target {
    return { label: this.st.label, axis: this.st.axis };
  }

  private labelOf(id: number): Label {
    return this.labels.find((l) => l.id === id) ?? { id, name: `Label ${id}`, color: "#cccccc" };
  }

  // ---------- lifecycle ----------

  /** Load everything and show the cell. */
  async start(): Promise<void> {
    document.addEventListener("keydown", this.keyHandler);
    const api = this.host.api;
    const [hist, methods] = await Promise.all([
      api.histogram(this.cell.id).catch(() => null),
      api.methods().catch(() => [] as Method[]),
    ]);
    this.methods = methods;
    this.display.init(hist);
    fillPresets(this.el.preset, this.display.presets);
    this.fillLabels();
    this.fillMethods();
    this.applyWindow(false);
    await this.tracings.reload(this.target);
    this.placeViews();
    this.syncControls();
    await this.refreshAll();
    if (this.tracings.drawn.size > 0) void this.runPreview(false);
    this.advisor.refresh();
    this.evalPanel.start();
    this.ready = true;
    this.time.start();
    this.views.observeResize();
    void this.tracingSummary.refresh();
  }

  /** Stop timers and listeners (when leaving the screen). */
  dispose(): void {
    if (this.disposed) return;
    this.disposed = true;
    document.removeEventListener("keydown", this.keyHandler);
    this.time.stop();
    this.tracingSummary.dispose();
    this.views.dispose();
    this.panel3d.dispose();
    this.saveState();
  }

  private fillLabels(): void {
    fillLabels(this.el.label, this.labels);
    this.el.label.value = String(this.st.label);
    this.el.swatch.style.background = this.labelOf(this.st.label).color;
  }

  private fillMethods(): void {
    fillMethods(this.el.method, this.methods);
    if (!this.methods.some((m) => m.name === this.st.method)) this.st.method = "";
    this.el.method.value = this.st.method;
  }

  private syncControls(): void {
    const e = this.el;
    e.axis.value = this.st.axis;
    e.sliceIndex.max = String(this.depth - 1);
    e.sliceIndex.value = String(this.index);
    e.sliceMax.textContent = `/ ${this.depth - 1}`;
    e.skip.value = String(this.st.skip);
    e.label.value = String(this.st.label);
    e.swatch.style.background = this.labelOf(this.st.label).color;
    e.wlo.value = windowText(this.display.win.lo, this.cell.dtype);
    e.whi.value = windowText(this.display.win.hi, this.cell.dtype);
    e.preset.value = this.display.presetShown();
  }

  private placeViews(): void {
    this.views.place(this.el, this.st.axis);
    this.el.main.append(this.el.suggest);
  }

  // ---------- window/level ----------

  private applyWindow(repaint = true): void {
    this.views.setWindow(this.display.update());
    if (repaint) this.syncControls();
    this.saveState();
    if (repaint) this.paintAll();
  }

  /** The base window changed: brightness and contrast were reset. */
  private baseChanged(): void {
    this.el.bright.value = "0";
    this.el.contrast.value = "0";
    this.applyWindow();
  }

  private choosePreset(id: string): void {
    if (this.display.choosePreset(id)) this.baseChanged();
  }

  private autoWin(): void {
    this.choosePreset("auto");
  }

  // ---------- slices and painting ----------

  /** Load the three views' slices and paint. */
  private async refreshAll(): Promise<void> {
    await this.views.refreshAll();
    this.updateStatus();
  }

  private paintAll(): void {
    this.views.paintAll();
  }

  private paintView(a: Axis): void {
    this.views.paint(a);
  }

  /** What view `a` paints over slice `idx`. */
  private overlay(a: Axis, idx: number, working: boolean): Overlay {
    const t: Traced = {
      contours: this.tracings.contours,
      // An array: the working view reads it twice (contours, tints).
      previews: [...this.previews.all()],
      axis: this.st.axis,
      label: this.st.label,
      colorOf: (l) => this.labelOf(l).color,
    };
    const evaluation = this.evalPanel.overlayFor(a, idx);
    if (!working) return { tints: [], contours: [], rects: cutRects(t, a, this.st.focus), stroke: null, evaluation };
    const drawnHere = this.tracings.drawn.has(idx);
    const contours = workingContours(t, idx, drawnHere);
    const tints = this.st.uncertainty ? uncertainTints(t, idx, drawnHere) : [];
    return { tints, contours, rects: [], stroke: this.pen.stroke, evaluation };
  }

  // ---------- navigation ----------

  /** Go to slice `index` of the working axis (clamped). */
  async goto(index: number): Promise<void> {
    if (!Number.isFinite(index)) return;
    const i = Math.min(this.depth - 1, Math.max(0, Math.round(index)));
    this.pen.cancelPending();
    const t0 = performance.now();
    this.st.focus[axisDim(this.st.axis)] = i;
    this.saveState();
    this.syncControls();
    await this.views.refresh(this.st.axis);
    // The slice's picture is painted at the next frame: measure to it.
    await new Promise((r) => requestAnimationFrame(() => r(null)));
    this.figures.sliceSwitch.push(performance.now() - t0);
    AXES.filter((a) => a !== this.st.axis).forEach((a) => this.paintView(a));
    this.updateStatus();
    this.prefetch();
  }

  private prefetch(): void {
    const near = [this.st.skip, -this.st.skip, 1, -1].map((d) => this.index + d);
    this.views.prefetch(
      this.st.axis,
      near.filter((j) => j >= 0 && j < this.depth),
    );
  }

  /** Move by `n` slices. */
  step(n: number): void {
    void this.goto(this.index + n);
  }

  /** Reload the drawn slices of the new target, paint, and preview it if it has none yet. */
  private targetChanged(): void {
    void this.tracings.reloadDrawn(this.target).then(() => {
      this.paintAll();
      this.updateStatus();
      this.showMethodNote();
      const { label, axis } = this.target;
      if (this.tracings.drawn.size > 0 && !this.previews.get(label, axis)) void this.runPreview(false);
      this.advisor.refresh();
    });
  }

  /** Trace on another axis. */
  setAxis(a: Axis): void {
    if (a === this.st.axis) return;
    this.pen.cancel();
    this.st.axis = a;
    this.saveState();
    this.placeViews();
    this.syncControls();
    this.targetChanged();
    void this.refreshAll();
  }

  /** Choose the component being traced. */
  setLabel(id: number): void {
    if (!this.labels.some((l) => l.id === id)) return;
    this.pen.cancel();
    this.st.label = id;
    this.saveState();
    this.syncControls();
    this.targetChanged();
    void this.tracingSummary.refresh();
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
    this.pen.cancel();
    void this.refreshAll();
  }

  private async addLabel(): Promise<void> {
    const input = this.el.newLabel;
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
      const next = others
        .map((c) => ({ c, d: (order.indexOf(c.id) - here + order.length) % order.length }))
        .sort((a, b) => a.d - b.d)[0].c;
      this.host.openCell(next.id);
    } catch (e) {
      this.host.toast(`next cell: ${(e as Error).message}`, true);
    }
  }

  // ---------- drawing ----------

  /** *Add contour*: finish the red contour (closing it) and save it. */
  addContour(): void {
    this.pen.finish();
  }

  private commit(c: FinishedContour): void {
    const points = c.points.map(([u, v]) => [round3(u), round3(v)] as Vec2);
    const body = {
      ...this.target,
      index: this.index,
      points,
      pressure: c.pressure,
      times_ms: c.times_ms,
      tool: c.tool,
    };
    this.previews.changed();
    const clientId = newClientId();
    this.committedAt.set(clientId, performance.now());
    this.tracings.add(body, clientId);
    this.recompute();
    if (this.cell.status === "not_started") void this.setDone(false);
  }

  /** Clear this label's contours on the slice (undoable). */
  clearContours(): void {
    this.pen.cancel();
    this.previews.changed();
    this.tracings.clear(this.target, this.index);
    this.recompute();
  }

  /** The component is absent on this slice. */
  markEmpty(): void {
    this.pen.cancel();
    this.previews.changed();
    this.tracings.markEmpty(this.target, this.index);
    this.recompute();
  }

  private async undoRedo(which: "undo" | "redo"): Promise<void> {
    this.pen.cancel();
    try {
      if (!(await this.tracings.undoRedo(which))) {
        this.host.toast(which === "undo" ? "nothing to undo" : "nothing to redo");
        return;
      }
      this.previews.changed();
      await this.tracings.reload(this.target);
      this.paintAll();
      this.updateStatus();
      this.previews.schedule();
      this.advisor.refresh();
      this.tracingSummary.schedule();
    } catch (e) {
      this.host.toast(e instanceof ChangesPending ? e.message : `${which}: ${(e as Error).message}`, true);
    }
  }

  /** Called by the app when the outbox acknowledged an operation of this cell. */
  onSent(op: Op, answer: unknown): void {
    if (op.cell !== this.cell.id) return;
    const t0 = this.committedAt.get(op.client_id);
    if (t0 !== undefined) {
      this.figures.saveLatency.push(performance.now() - t0);
      this.committedAt.delete(op.client_id);
    }
    if (this.tracings.acknowledged(op, answer)) this.recompute();
    else void this.tracings.reload(this.target).then(() => this.paintAll());
    const label = op.kind === "contour" ? op.body.label : op.label;
    const axis = op.kind === "contour" ? op.body.axis : op.axis;
    if (label === this.st.label) this.tracingSummary.schedule();
    if (label === this.st.label && axis === this.st.axis && this.host.outbox.pending.length === 0) {
      this.previews.schedule();
      this.advisor.refresh();
    }
  }

  /** Called when the outbox changed. */
  onQueue(n: number, err?: string): void {
    const u = this.el.unsaved;
    u.textContent =
      n > 0 ? `${n} change${n > 1 ? "s" : ""} not saved yet${err ? ` (${err}) — retrying` : ""}` : "all changes saved";
    u.className = n > 0 ? "unsaved warn" : "unsaved ok";
    if (n > 0 || err) this.recompute();
  }

  private recompute(): void {
    this.tracings.recompute();
    this.paintAll();
    this.updateStatus();
  }

  // ---------- interpolation ----------

  /** Interpolate the current label along the working axis and show it dashed. */
  runPreview(explicit: boolean): Promise<void> {
    return this.previews.run(explicit);
  }

  private showPreview(label: number, r: InterpResult | null, explicit: boolean): void {
    if (!r) {
      this.el.volume.textContent = "";
      this.showMethodNote();
      if (explicit) this.host.toast("draw at least one contour first");
      return;
    }
    this.el.volume.textContent = `${this.labelOf(label).name}: ${fmtNum(r.volume)} ${r.unit} (${r.method})`;
    this.showMethodNote();
    this.paintAll();
    this.methodMayHaveChanged();
  }

  /**
   * Ask the advice and the summary again when the method in use is no
   * longer the one they were last asked for (another method picked, or the
   * preview's leave-one-out recommending another): both report the
   * predicted Dice of that method.
   */
  private methodMayHaveChanged(): void {
    const m = this.methodInUse;
    if (m === this.methodAsked) return;
    this.methodAsked = m;
    this.advisor.refresh();
    void this.tracingSummary.refresh();
  }

  /** Which method the preview of the current label used and why (with "recommended" chosen). */
  private showMethodNote(): void {
    const r = this.previews.get(this.st.label, this.st.axis);
    this.el.methodNote.textContent = methodNote(r, this.st.method);
  }

  /** Turn the uncertainty tint on or off; on, the preview is asked again with its confidence. */
  setUncertainty(on: boolean): void {
    this.st.uncertainty = on;
    this.el.uncertainty.checked = on;
    this.saveState();
    this.paintAll();
    if (on && this.tracings.drawn.size > 0) void this.runPreview(false);
  }

  /** Show or hide the 3D view. */
  toggle3d(on?: boolean): Promise<void> {
    return this.panel3d.toggle(on);
  }

  /** Every component with contours on the working axis, outer (lower label) first. */
  private async surfaces(): Promise<Surface[]> {
    const axis = this.st.axis;
    const labels = [...new Set(this.tracings.contours.filter((c) => c.axis === axis).map((c) => c.label))].sort(
      (a, b) => a - b,
    );
    const surfaces: Surface[] = [];
    for (const l of labels) {
      const res = await this.previews.ensure(l, axis, this.st.method);
      const mesh = await this.host.api.mesh(this.cell.id, res.result_id);
      surfaces.push({ name: this.labelOf(l).name, color: this.labelOf(l).color, mesh });
    }
    return surfaces;
  }

  // ---------- status & keys ----------

  private updateStatus(): void {
    let voxel = "—";
    let value = "—";
    if (this.cursor) {
      const v = this.views.views[this.cursor.axis];
      const px = pixelAt(this.cursor.u, this.cursor.v, v.size[0], v.size[1]);
      if (px) {
        const [i, j, k] = voxelOf(this.cursor.axis, v.index, px[0], px[1]);
        voxel = `(${i}, ${j}, ${k})`;
        if (v.image) value = formatValue(v.image.raw[px[0] + v.image.width * px[1]], this.cell.dtype);
      }
    }
    const line = statusLine(
      {
        axis: this.st.axis,
        index: this.index,
        depth: this.depth,
        voxel,
        value,
        label: this.labelOf(this.st.label),
        drawn: this.tracings.drawn.get(this.index),
        drawnCount: this.tracings.drawn.size,
        preview: this.previews.get(this.st.label, this.st.axis) !== undefined,
        seconds: this.time.seconds,
      },
      () => (this.el.help.hidden = false),
    );
    this.el.status.replaceChildren(...line);
  }

  private onKey(e: KeyboardEvent): void {
    const t = e.target;
    const typing = t instanceof HTMLInputElement || t instanceof HTMLTextAreaElement || t instanceof HTMLSelectElement;
    if (typing && !(e.key === "Escape")) return;
    const act = actionOf(e);
    if (!act) return;
    e.preventDefault();
    this.time.touch();
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
        this.pen.cancel();
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
      case "goto-suggested": {
        const next = this.advisor.next(this.st.label, this.st.axis);
        if (next === null) this.host.toast("no suggested slice yet: trace at least two slices");
        else void this.goto(next);
        return;
      }
      case "axis-x":
      case "axis-y":
      case "axis-z":
        return this.setAxis(act.slice(5) as Axis);
      case "zoom-in":
        return this.views.views[this.st.axis].zoom(1.25);
      case "zoom-out":
        return this.views.views[this.st.axis].zoom(0.8);
      case "zoom-fit":
        return this.views.fit();
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
      case "toggle-uncertainty":
        return this.setUncertainty(!this.st.uncertainty);
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
    return this.views.sliceToClient(a, u, v);
  }

  /** Width and height of view `a`'s slices, and the slice it shows. */
  sliceSize(a: Axis): [number, number, number] {
    const v = this.views.views[a];
    return [v.size[0], v.size[1], v.index];
  }

  /** Resolves when every change is saved and no preview is running. */
  async idle(): Promise<void> {
    await this.host.outbox.flush();
    for (let n = 0; n < 600 && (!this.previews.idle || !this.advisor.idle || this.host.outbox.pending.length); n++)
      await new Promise((r) => setTimeout(r, 25));
  }

  /** A summary of the state (for the end-to-end test). */
  summary(): {
    axis: Axis;
    index: number;
    label: number;
    drawn: number[];
    empty: number[];
    contours: number;
    onSlice: number;
    preview: boolean;
    overlay: boolean;
    pending: number;
    suggested: number | null;
    method: string | null;
    recommended: string | null;
    uncertain: number;
  } {
    const res = this.previews.get(this.st.label, this.st.axis);
    return {
      axis: this.st.axis,
      index: this.index,
      label: this.st.label,
      ...this.tracings.summary(this.target, this.index),
      preview: this.previews.get(this.st.label, this.st.axis) !== undefined,
      overlay: this.views.views[this.st.axis].scene.overlay !== null,
      pending: this.host.outbox.pending.length,
      suggested: this.advisor.next(this.st.label, this.st.axis),
      method: res?.method ?? null,
      recommended: res?.recommended_method ?? null,
      uncertain: res?.slices.find((s) => s.index === this.index)?.uncertain?.length ?? 0,
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
