/**
 * The tracing summary of the side panel: slices traced, time spent and the
 * predicted Dice of the label being traced (`GET /api/cells/{cell}/summary`),
 * for the method the preview and the advice use (the one picked, else the
 * one leave-one-out recommended): the advice reports the same figure, so the
 * panel never shows two predicted Dice for one tracing.
 * It is refreshed a moment after the last saved change (debounced: a burst of
 * strokes asks once), one request at a time; a change during a request asks
 * for one more when it ends, as the preview does.
 */
import type { Api, TracingSummary } from "./api";

/** Quiet time after the last saved change before the summary is asked for. */
export const SUMMARY_DELAY_MS = 800;

/** The summary as one line: "5 traced slices, 1 empty · 12:30 min · predicted Dice 0.962". */
export function formatSummary(s: TracingSummary): string {
  const slices =
    `${s.traced_slices} traced slice${s.traced_slices === 1 ? "" : "s"}` +
    (s.empty_slices > 0 ? `, ${s.empty_slices} empty` : "");
  const total = Math.round(s.seconds);
  const time = `${Math.floor(total / 60)}:${String(total % 60).padStart(2, "0")} min`;
  const dice =
    s.predicted_dice === null || s.predicted_dice === undefined
      ? "predicted Dice after 3 drawn slices"
      : `predicted Dice ${s.predicted_dice.toFixed(3)}`;
  return `${slices} · ${time} · ${dice}`;
}

/** The summary line of one cell, for the label being traced. */
export class SummaryPanel {
  private timer: ReturnType<typeof setTimeout> | null = null;
  private busy = false;
  private again = false;
  private disposed = false;

  constructor(
    private api: Api,
    private cellId: string,
    private label: () => number,
    private method: () => string,
    private el: HTMLElement,
  ) {}

  /** Refresh after [`SUMMARY_DELAY_MS`] without a further call. */
  schedule(): void {
    if (this.disposed) return;
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = setTimeout(() => {
      this.timer = null;
      void this.refresh();
    }, SUMMARY_DELAY_MS);
  }

  /** Ask for the summary now and show it. */
  async refresh(): Promise<void> {
    if (this.busy) {
      this.again = true;
      return;
    }
    this.busy = true;
    const label = this.label();
    try {
      const s = await this.api.summary(this.cellId, label, this.method() || undefined);
      if (!this.disposed && label === this.label()) this.el.textContent = formatSummary(s);
    } catch (e) {
      if (!this.disposed) this.el.textContent = `summary: ${(e as Error).message}`;
    } finally {
      this.busy = false;
    }
    if (this.again && !this.disposed) {
      this.again = false;
      void this.refresh();
    }
  }

  /** Stop the pending refresh (when leaving the screen). */
  dispose(): void {
    this.disposed = true;
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = null;
  }
}
