/**
 * The 3D slot of the tracing screen: hidden until clicked (or D), then the
 * interpolated surfaces of every traced component, updated after each
 * preview. three.js is loaded only when the view is first shown.
 */
import type { Surface, Viewer3D } from "./view3d";

/** The elements of the 3D slot. */
export interface Slot3D {
  /** The slot (gets the class "on" while shown). */
  v3d: HTMLDivElement;
  /** Where the viewer's canvas goes. */
  v3dHost: HTMLDivElement;
  /** The line of text over it. */
  v3dMsg: HTMLDivElement;
}

/** The text of the slot while the view is off. */
export const PROMPT_3D = "3D view — click to show the interpolated surfaces (D)";

/** The 3D view of the tracing screen. */
export class Panel3D {
  private viewer: Viewer3D | null = null;
  /** Whether the view is shown. */
  on = false;

  constructor(
    private el: Slot3D,
    /** The surfaces to show (computed on demand). */
    private surfaces: () => Promise<Surface[]>,
    /** Called after new surfaces were shown. */
    private shown: () => void,
  ) {}

  /** Show or hide the view. */
  async toggle(on = !this.on): Promise<void> {
    this.on = on;
    this.el.v3d.classList.toggle("on", on);
    if (!on) {
      this.dispose();
      this.el.v3dMsg.textContent = PROMPT_3D;
      this.el.v3dMsg.hidden = false;
      return;
    }
    await this.update();
  }

  /** Recompute and show the surfaces. */
  async update(): Promise<void> {
    this.el.v3dMsg.hidden = false;
    this.el.v3dMsg.textContent = "computing surfaces…";
    try {
      const { Viewer3D } = await import("./view3d");
      if (!this.viewer) this.viewer = new Viewer3D(this.el.v3dHost);
      const surfaces = await this.surfaces();
      if (!this.on) return;
      this.viewer.show(surfaces);
      this.el.v3dMsg.textContent = surfaces.length ? surfaces.map((s) => s.name).join(" · ") : "nothing traced yet";
      this.shown();
    } catch (e) {
      this.el.v3dMsg.textContent = `3D: ${(e as Error).message}`;
    }
  }

  /** Release the viewer. */
  dispose(): void {
    this.viewer?.dispose();
    this.viewer = null;
  }
}
