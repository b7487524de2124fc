/**
 * Time spent tracing a cell: counted second by second while the page is
 * visible and the user gave input in the last minute, sent to the server
 * every 20 s and when the screen is left (a request that outlives the page).
 */
import type { Api } from "./api";

/** Seconds without input after which the clock stops. */
const IDLE_MS = 60000;
/** How often the counted seconds are sent. */
const SEND_MS = 20000;

/** The tracing clock of one cell. */
export class TimeTracker {
  /** Seconds spent on the cell (the server's total plus what was counted since). */
  seconds = 0;
  private unsent = 0;
  private lastInput = performance.now();
  private timers: number[] = [];

  constructor(
    private api: Api,
    private cellId: string,
    /** Called when `seconds` changed. */
    private changed: () => void,
  ) {}

  /** Start counting and fetch the server's total. */
  start(): void {
    this.timers.push(
      window.setInterval(() => {
        if (document.visibilityState === "visible" && performance.now() - this.lastInput < IDLE_MS) {
          this.seconds++;
          this.unsent++;
          this.changed();
        }
      }, 1000),
      window.setInterval(() => void this.flush(), SEND_MS),
    );
    this.api.addTime(this.cellId, 0).then(
      (r) => {
        this.seconds = Math.max(this.seconds, r.total_seconds ?? 0);
        this.changed();
      },
      () => {},
    );
  }

  /** The user did something. */
  touch(): void {
    this.lastInput = performance.now();
  }

  /** Stop counting and send what is left (also when the page is being closed). */
  stop(): void {
    this.timers.forEach((t) => clearInterval(t));
    this.timers = [];
    void this.flush(true);
  }

  private async flush(leaving = false): Promise<void> {
    const s = this.unsent;
    if (s <= 0) return;
    this.unsent = 0;
    try {
      const r = await this.api.addTime(this.cellId, s, leaving);
      if (!leaving && typeof r?.total_seconds === "number") this.seconds = Math.max(this.seconds, r.total_seconds);
    } catch {
      this.unsent += s;
    }
  }
}
