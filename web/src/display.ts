/**
 * The display window of the tracing screen: the presets a cell offers, the
 * base window (a preset's or one typed in by hand) and brightness/contrast
 * on top of it. The choices live in the view settings so they persist.
 */
import type { ViewState } from "./viewstate";
import {
  AUTO_PRESET,
  applyBrightnessContrast,
  defaultPreset,
  presetWindow,
  presetsFor,
  type Dtype,
  type Histogram,
  type Preset,
  type Window,
} from "./windowing";

/** What the window needs to know of the cell. */
export interface WindowedCell {
  dtype: Dtype;
  min: number;
  max: number;
}

/** The window state of one cell. */
export class DisplayWindow {
  private hist: Histogram | null = null;
  private baseWin: Window = { lo: 0, hi: 255 };
  /** The presets this cell offers. */
  presets: Preset[] = [AUTO_PRESET];
  /** The window in force (base window with brightness and contrast). */
  win: Window = { lo: 0, hi: 255 };

  constructor(
    private cell: WindowedCell,
    private st: ViewState,
  ) {}

  /** Take the cell's histogram (null when unavailable) and set the base window from the settings. */
  init(hist: Histogram | null): void {
    this.hist = hist;
    this.presets = presetsFor(hist, this.cell.dtype);
    this.baseWin = this.baseWindow();
  }

  /** Recompute the window in force from the base window, brightness and contrast. */
  update(): Window {
    this.win = applyBrightnessContrast(this.baseWin, this.st.brightness, this.st.contrast);
    return this.win;
  }

  /** The preset in force: the chosen one when this cell offers it, else the cell's default. */
  currentPreset(): Preset {
    return this.presets.find((p) => p.id === this.st.preset) ?? defaultPreset(this.hist, this.cell.dtype);
  }

  /** The id shown in the preset menu. */
  presetShown(): string {
    return this.st.preset === "manual" ? "manual" : this.currentPreset().id;
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
  }

  /** Choose a preset; false when the cell does not offer it. */
  choosePreset(id: string): boolean {
    const p = this.presets.find((q) => q.id === id);
    if (!p) return false;
    this.st.preset = p.id;
    this.st.manual = null;
    this.setBase(presetWindow(p, this.hist, this.cell));
    return true;
  }

  /** A window typed in by hand; false when it is not a window (not finite, or high ≤ low). */
  setManual(lo: number, hi: number): boolean {
    if (!(Number.isFinite(lo) && Number.isFinite(hi) && hi > lo)) return false;
    this.st.preset = "manual";
    this.st.manual = { lo, hi };
    this.setBase({ lo, hi });
    return true;
  }
}
