/**
 * The evaluation panel: run an automated segmentation of the cell, compare
 * it with the user's interpolated ground truth (metrics table), show the
 * false positives and false negatives on the slices, and rate it.
 */
import type { Api, CellDetail, Label, Me, Metrics, Rating, Segmentation } from "./api";
import { clear, h } from "./dom";
import type { Axis } from "./transform";

/** What the panel needs from the tracing screen. */
export interface EvalContext {
  api: Api;
  me: Me;
  cell: CellDetail;
  /** The current label. */
  label(): number;
  /** All labels. */
  labels(): Label[];
  /** The overlay to show changed (repaint). */
  overlayChanged(): void;
  /** Report a message. */
  toast(msg: string, error?: boolean): void;
}

/** Rows of the metrics table: key, title, kind. */
const ROWS: [string, string, "ratio" | "count" | "dist" | "vol"][] = [
  ["dice", "Dice", "ratio"],
  ["jaccard", "Jaccard", "ratio"],
  ["sensitivity", "Sensitivity", "ratio"],
  ["specificity", "Specificity", "ratio"],
  ["precision", "Precision", "ratio"],
  ["volume_similarity", "Volume similarity", "ratio"],
  ["hd", "Hausdorff", "dist"],
  ["hd95", "HD95", "dist"],
  ["assd", "ASSD", "dist"],
  ["nsd", "NSD", "ratio"],
  ["volume_gt", "Volume (ground truth)", "vol"],
  ["volume_seg", "Volume (segmentation)", "vol"],
  ["tp", "TP voxels", "count"],
  ["fp", "FP voxels", "count"],
  ["fn", "FN voxels", "count"],
];

/** Format one metric. */
export function formatMetric(
  v: Metrics[string] | undefined,
  kind: "ratio" | "count" | "dist" | "vol",
  unit: string,
): string {
  if (v === null || v === undefined) return "—";
  if (typeof v !== "number") return String(v);
  switch (kind) {
    case "ratio":
      return v.toFixed(4);
    case "count":
      return v.toLocaleString("en-US");
    case "dist":
      return `${v.toFixed(3)} ${unit}`;
    case "vol":
      return `${v.toFixed(1)} ${unit}³`;
  }
}

/** The panel. */
export class EvalPanel {
  /** The panel element (a side section). */
  readonly root: HTMLElement;
  private segs: Segmentation[] = [];
  private segSel: HTMLSelectElement;
  private table: HTMLElement;
  private ratings: HTMLElement;
  private showOverlay: HTMLInputElement;
  private overlays = new Map<string, Uint8Array | "loading" | "error">();
  private score = 0;
  private stars: HTMLButtonElement[] = [];
  private comment: HTMLTextAreaElement;

  constructor(private ctx: EvalContext) {
    const method = h(
      "select",
      { testid: "seg-method", title: "Automated segmentation method" },
      ...["otsu", "rosin", "kmeans", "multi-otsu"].map((m) => h("option", { value: m }, m)),
    );
    const smooth = h("input", {
      type: "number",
      min: "0",
      step: "0.5",
      value: "1",
      class: "num",
      title: "Gaussian smoothing σ in voxels before thresholding",
    });
    const largest = h("input", { type: "checkbox", checked: true, id: "seg-largest" });
    const fill = h("input", { type: "checkbox", checked: true, id: "seg-fill" });
    this.segSel = h("select", { testid: "seg-select", onchange: () => this.selectionChanged() });
    this.table = h("div", { class: "metrics", testid: "metrics-table" });
    this.ratings = h("div", { class: "ratings small" });
    this.showOverlay = h("input", {
      type: "checkbox",
      id: "show-overlay",
      testid: "show-overlay",
      onchange: () => this.selectionChanged(),
    });
    this.comment = h("textarea", { rows: 2, placeholder: "comment", testid: "rating-comment" });
    const starBox = h("span", { class: "stars", testid: "rating-stars" });
    for (let s = 1; s <= 5; s++) {
      const b = h("button", { class: "star", title: `${s} of 5`, onclick: () => this.setScore(s) }, "☆");
      this.stars.push(b);
      starBox.append(b);
    }
    this.root = h(
      "section",
      { class: "eval", testid: "eval-panel" },
      h("h3", {}, "Evaluate a segmentation"),
      h("div", { class: "row" }, method, h("label", { title: "smoothing σ" }, "σ"), smooth),
      h(
        "div",
        { class: "row small" },
        largest,
        h("label", { for: "seg-largest" }, "largest component"),
        fill,
        h("label", { for: "seg-fill" }, "fill holes"),
      ),
      h(
        "div",
        { class: "row" },
        h(
          "button",
          {
            testid: "seg-run",
            onclick: () => void this.run(method.value, Number(smooth.value), largest.checked, fill.checked),
          },
          "Run segmentation",
        ),
      ),
      h("div", { class: "row" }, this.segSel),
      h(
        "div",
        { class: "row" },
        h(
          "button",
          { testid: "evaluate", class: "primary", onclick: () => void this.evaluate() },
          "Compare with my ground truth",
        ),
      ),
      h(
        "div",
        { class: "row small" },
        this.showOverlay,
        h("label", { for: "show-overlay" }, "FP "),
        h("i", { class: "swatch fp" }),
        h("label", { for: "show-overlay" }, " / FN "),
        h("i", { class: "swatch fn" }),
        h("label", { for: "show-overlay" }, " on slices"),
      ),
      this.table,
      h("div", { class: "row" }, starBox),
      h("div", { class: "row" }, this.comment),
      h(
        "div",
        { class: "row" },
        h("button", { testid: "rating-save", onclick: () => void this.rate() }, "Save rating"),
      ),
      this.ratings,
    );
  }

  /** Load the segmentations and ratings. */
  start(): void {
    void this.reload();
  }

  private async reload(selectId?: string | number): Promise<void> {
    try {
      this.segs = await this.ctx.api.segmentations(this.ctx.cell.id);
    } catch {
      this.segs = [];
    }
    const prev = selectId ?? this.segSel.value;
    clear(this.segSel);
    if (this.segs.length === 0) this.segSel.append(h("option", { value: "" }, "no segmentation yet"));
    for (const s of this.segs)
      this.segSel.append(h("option", { value: String(s.id) }, `${s.name || s.method} (${s.method})`));
    if (prev !== undefined && this.segs.some((s) => String(s.id) === String(prev))) this.segSel.value = String(prev);
    this.selectionChanged();
  }

  private selected(): Segmentation | undefined {
    return this.segs.find((s) => String(s.id) === this.segSel.value);
  }

  private selectionChanged(): void {
    this.overlays.clear();
    void this.loadRatings();
    this.ctx.overlayChanged();
  }

  /** Show or hide the FP/FN overlay. */
  toggleOverlay(): void {
    this.showOverlay.checked = !this.showOverlay.checked;
    this.selectionChanged();
  }

  /**
   * The overlay of a slice when it is shown and loaded; starts loading it
   * otherwise (the view repaints when it arrives).
   */
  overlayFor(axis: Axis, index: number): Uint8Array | null {
    const seg = this.selected();
    if (!this.showOverlay.checked || !seg) return null;
    const key = `${this.ctx.label()}/${seg.id}/${axis}/${index}`;
    const o = this.overlays.get(key);
    if (o instanceof Uint8Array) return o;
    if (o === undefined) {
      this.overlays.set(key, "loading");
      this.ctx.api.overlay(this.ctx.cell.id, axis, index, this.ctx.label(), seg.id).then(
        (d) => {
          this.overlays.set(key, d);
          if (this.overlays.size > 600) this.overlays.delete(this.overlays.keys().next().value as string);
          this.ctx.overlayChanged();
        },
        (e) => {
          this.overlays.set(key, "error");
          this.ctx.toast(`overlay: ${(e as Error).message}`, true);
        },
      );
    }
    return null;
  }

  private async run(method: string, smooth: number, largest: boolean, fill: boolean): Promise<void> {
    this.table.replaceChildren(h("p", { class: "muted" }, `running ${method}…`));
    try {
      const body: {
        method: string;
        smooth?: number;
        largest_component: boolean;
        fill_holes: boolean;
        classes?: number;
      } = { method, largest_component: largest, fill_holes: fill };
      if (smooth > 0) body.smooth = smooth;
      if (method === "multi-otsu") body.classes = 3;
      const s = await this.ctx.api.segment(this.ctx.cell.id, body);
      this.table.replaceChildren();
      await this.reload(s.id);
    } catch (e) {
      this.table.replaceChildren(h("p", { class: "err" }, `segmentation: ${(e as Error).message}`));
    }
  }

  private async evaluate(): Promise<void> {
    const seg = this.selected();
    if (!seg) {
      this.ctx.toast("run or choose a segmentation first", true);
      return;
    }
    const label = this.ctx.label();
    this.table.replaceChildren(h("p", { class: "muted" }, "comparing…"));
    try {
      const m = await this.ctx.api.evaluate(this.ctx.cell.id, {
        label,
        reference: { user: this.ctx.me.name },
        test: { segmentation: seg.id },
      });
      this.showMetrics(m, seg);
      if (!this.showOverlay.checked) this.toggleOverlay();
    } catch (e) {
      this.table.replaceChildren(h("p", { class: "err" }, `evaluation: ${(e as Error).message}`));
    }
  }

  private showMetrics(m: Metrics, seg: Segmentation): void {
    const unit = this.ctx.cell.unit || "";
    const lname = this.ctx.labels().find((l) => l.id === this.ctx.label())?.name ?? `label ${this.ctx.label()}`;
    const rows = ROWS.filter(([k]) => k in m).map(([k, title, kind]) =>
      h("tr", {}, h("th", {}, title), h("td", { "data-key": k }, formatMetric(m[k], kind, unit))),
    );
    // An empty reference makes every overlap figure 0 or undefined: say why.
    const noTruth =
      m.volume_gt === 0
        ? h(
            "p",
            { class: "warn", testid: "metrics-warning" },
            `Your ${lname} is empty on this cell: trace it (or choose another component) before comparing.`,
          )
        : null;
    this.table.replaceChildren(
      ...(noTruth ? [noTruth] : []),
      h("table", {}, h("caption", {}, `${seg.method} vs ${this.ctx.me.name}'s ${lname}`), h("tbody", {}, ...rows)),
    );
  }

  private setScore(s: number): void {
    this.score = s;
    this.stars.forEach((b, i) => {
      b.textContent = i < s ? "★" : "☆";
      b.classList.toggle("on", i < s);
    });
  }

  private async rate(): Promise<void> {
    const seg = this.selected();
    if (!seg) return this.ctx.toast("choose a segmentation to rate", true);
    if (this.score < 1) return this.ctx.toast("choose 1 to 5 stars", true);
    try {
      await this.ctx.api.rate(this.ctx.cell.id, {
        segmentation: seg.id,
        score: this.score,
        comment: this.comment.value.trim(),
      });
      this.ctx.toast("rating saved");
      this.comment.value = "";
      this.setScore(0);
      await this.loadRatings();
    } catch (e) {
      this.ctx.toast(`rating: ${(e as Error).message}`, true);
    }
  }

  private async loadRatings(): Promise<void> {
    const seg = this.selected();
    if (!seg) {
      this.ratings.replaceChildren();
      return;
    }
    try {
      const all: Rating[] = await this.ctx.api.ratings(this.ctx.cell.id);
      const mine = all.filter((r) => String(r.segmentation) === String(seg.id));
      this.ratings.replaceChildren(
        ...mine.map((r) =>
          h(
            "div",
            {},
            `${"★".repeat(r.score)}${"☆".repeat(5 - r.score)} ${r.user ?? ""} ${r.comment ? "— " + r.comment : ""}`,
          ),
        ),
      );
    } catch {
      this.ratings.replaceChildren();
    }
  }
}
