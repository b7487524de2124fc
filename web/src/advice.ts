/**
 * The next suggested slice: after each saved change of the label being
 * traced the server ranks the undrawn slices along the working axis
 * (`GET .../advice`, the model of `interslice advise`), and the screen shows
 * the best one on the working view with the key that goes there (G). The
 * optional "done when" hint says when one more slice is predicted to add
 * less Dice than the user's threshold. Like the preview, one request runs at
 * a time and changes made meanwhile ask for one more run.
 */
import type { Advice, Api } from "./api";
import type { Axis } from "./transform";

/** What the advice is about: the label being traced and its axis. */
export interface AdviceTarget {
  label: number;
  axis: Axis;
  method: string;
}

/** What the screen does around the advice. */
export interface AdviceHooks {
  target(): AdviceTarget;
  /** Show the new state (advice, or the reason there is none). */
  show(state: AdviceState): void;
}

/** The advice of the current target, or why there is none. */
export type AdviceState = { kind: "advice"; target: AdviceTarget; advice: Advice } | { kind: "none"; reason: string };

/** Where the "done when" threshold is kept (a fraction of Dice). */
const DONE_KEY = "interslice.doneWhen";
/** The default threshold: one more slice would add less than 0.5 % Dice. */
export const DEFAULT_DONE_WHEN = 0.005;

/** The user's "done when" threshold (0 turns the hint off). */
export function loadDoneWhen(store: Storage): number {
  const v = Number(store.getItem(DONE_KEY));
  return store.getItem(DONE_KEY) !== null && Number.isFinite(v) && v >= 0 && v < 1 ? v : DEFAULT_DONE_WHEN;
}

/** Keep the "done when" threshold. */
export function saveDoneWhen(store: Storage, v: number): void {
  store.setItem(DONE_KEY, String(v));
}

/**
 * Whether the tracing is done by the threshold: no suggested slice would add
 * as much. The largest gain, not the first suggestion's: on a short structure
 * the slices next to its ends come first by rule, whatever their gain.
 */
export function doneBy(advice: Advice, threshold: number): boolean {
  if (threshold <= 0) return false;
  return advice.suggestions.every((s) => s.dice_gain < threshold);
}

/** The advice of the label being traced, kept fresh. */
export class Advisor {
  private state: AdviceState = { kind: "none", reason: "" };
  private busy = false;
  private again = false;

  constructor(
    private api: Api,
    private cellId: string,
    private hooks: AdviceHooks,
  ) {}

  /** The best slice to trace next on `axis` for `label`, if advised. */
  next(label: number, axis: Axis): number | null {
    const s = this.state;
    if (s.kind !== "advice" || s.target.label !== label || s.target.axis !== axis) return null;
    return s.advice.suggestions[0]?.slice ?? null;
  }

  /** The current state. */
  get current(): AdviceState {
    return this.state;
  }

  /** Whether no request is running or asked for. */
  get idle(): boolean {
    return !this.busy && !this.again;
  }

  /** Ask the server again (coalesced with a running request). */
  refresh(): void {
    if (this.busy) {
      this.again = true;
      return;
    }
    void this.run();
  }

  private async run(): Promise<void> {
    this.busy = true;
    try {
      do {
        this.again = false;
        const target = this.hooks.target();
        try {
          const advice = await this.api.advice(this.cellId, target.label, target.axis, 3, target.method || undefined);
          this.state = { kind: "advice", target, advice };
        } catch (e) {
          this.state = { kind: "none", reason: (e as Error).message };
        }
        this.hooks.show(this.state);
      } while (this.again);
    } finally {
      this.busy = false;
    }
  }
}

/** The elements the advice is shown in. */
export interface AdviceElements {
  suggest: HTMLButtonElement;
  advice: HTMLElement;
}

/** Show the advice: the badge on the working view and the words in the side panel. */
export function renderAdvice(el: AdviceElements, state: AdviceState, doneWhen: number): void {
  if (state.kind === "none") {
    el.suggest.hidden = true;
    el.advice.textContent = state.reason ? `no suggestion yet: ${state.reason}` : "";
    el.advice.className = "small muted";
    return;
  }
  const { advice, target } = state;
  const best = advice.suggestions[0];
  const pct = (x: number) => `${(x * 100).toFixed(1)} %`;
  const done = doneBy(advice, doneWhen);
  const predicted = `predicted Dice ${advice.predicted_dice.toFixed(3)}`;
  el.suggest.hidden = best === undefined;
  el.suggest.classList.toggle("done", done);
  if (best) el.suggest.textContent = `next: ${target.axis} = ${best.slice} (G)`;
  el.suggest.dataset.slice = best ? String(best.slice) : "";
  el.advice.className = done ? "small advice-done" : "small";
  el.advice.textContent = best
    ? `Next suggested slice: ${target.axis} = ${best.slice} (+${pct(best.dice_gain)} Dice); ${predicted}` +
      (done ? `. Done: one more slice would add less than ${pct(doneWhen)}.` : "")
    : `Every slice is drawn; ${predicted}.`;
}
