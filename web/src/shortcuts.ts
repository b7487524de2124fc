/**
 * Keyboard shortcuts of the tracing screen: one table used both to dispatch
 * key presses and to print the help overlay, so the two never disagree.
 */

/** The actions a key can trigger. */
export type Action =
  | "next-slice"
  | "prev-slice"
  | "next-slice-1"
  | "prev-slice-1"
  | "add-contour"
  | "cancel-stroke"
  | "clear-contours"
  | "mark-empty"
  | "undo"
  | "redo"
  | "interpolate"
  | "goto-suggested"
  | "axis-x"
  | "axis-y"
  | "axis-z"
  | "zoom-in"
  | "zoom-out"
  | "zoom-fit"
  | "auto-window"
  | "next-cell"
  | "toggle-3d"
  | "toggle-overlay"
  | "toggle-uncertainty"
  | "help"
  | `label-${number}`;

/** One shortcut: the keys (as shown) and the action. */
export interface Shortcut {
  /** Keys shown in the help, e.g. "Ctrl+Z". */
  keys: string;
  /** What it does. */
  help: string;
  /** The action. */
  action: Action;
}

/** The shortcut table (help order). */
export const SHORTCUTS: Shortcut[] = [
  { keys: "→ / PageDown / .", help: "Next slice (by the skip step)", action: "next-slice" },
  { keys: "← / PageUp / ,", help: "Previous slice (by the skip step)", action: "prev-slice" },
  { keys: "Shift+→ / ↑", help: "Next slice (step 1)", action: "next-slice-1" },
  { keys: "Shift+← / ↓", help: "Previous slice (step 1)", action: "prev-slice-1" },
  { keys: "Enter / A", help: "Add contour (finish the red one)", action: "add-contour" },
  { keys: "Esc", help: "Discard the red contour", action: "cancel-stroke" },
  { keys: "C", help: "Clear all contours of the label on this slice", action: "clear-contours" },
  { keys: "E", help: "Mark empty (structure absent on this slice)", action: "mark-empty" },
  { keys: "Ctrl+Z", help: "Undo", action: "undo" },
  { keys: "Ctrl+Shift+Z / Ctrl+Y", help: "Redo", action: "redo" },
  { keys: "I", help: "Interpolate now", action: "interpolate" },
  { keys: "G", help: "Go to the next suggested slice", action: "goto-suggested" },
  { keys: "X / Y / Z", help: "Trace on the x, y or z view", action: "axis-z" },
  { keys: "1 … 9", help: "Choose the component (label)", action: "label-1" },
  { keys: "+ / −", help: "Zoom in / out (or the mouse wheel)", action: "zoom-in" },
  { keys: "0", help: "Fit the slice to the view", action: "zoom-fit" },
  { keys: "W", help: "Automatic window/level from the histogram", action: "auto-window" },
  { keys: "D", help: "Show or hide the 3D view", action: "toggle-3d" },
  { keys: "O", help: "Show or hide the FP/FN overlay", action: "toggle-overlay" },
  { keys: "U", help: "Show or hide the uncertainty tint of the preview", action: "toggle-uncertainty" },
  { keys: "N", help: "Next cell", action: "next-cell" },
  { keys: "?", help: "This help", action: "help" },
];

/** The subset of a KeyboardEvent read here. */
export interface KeyLike {
  key: string;
  ctrlKey: boolean;
  metaKey: boolean;
  shiftKey: boolean;
  altKey: boolean;
}

/** The action of a key press, or null. Space and drag are handled by the views. */
export function actionOf(e: KeyLike): Action | null {
  const mod = e.ctrlKey || e.metaKey;
  const k = e.key;
  if (mod) {
    const lk = k.toLowerCase();
    if (lk === "z") return e.shiftKey ? "redo" : "undo";
    if (lk === "y") return "redo";
    return null;
  }
  if (e.altKey) return null;
  switch (k) {
    case "ArrowRight":
      return e.shiftKey ? "next-slice-1" : "next-slice";
    case "ArrowLeft":
      return e.shiftKey ? "prev-slice-1" : "prev-slice";
    case "ArrowUp":
      return "next-slice-1";
    case "ArrowDown":
      return "prev-slice-1";
    case "PageDown":
    case ".":
      return "next-slice";
    case "PageUp":
    case ",":
      return "prev-slice";
    case "Enter":
    case "a":
    case "A":
      return "add-contour";
    case "Escape":
      return "cancel-stroke";
    case "c":
    case "C":
      return "clear-contours";
    case "e":
    case "E":
      return "mark-empty";
    case "i":
    case "I":
      return "interpolate";
    case "g":
    case "G":
      return "goto-suggested";
    case "x":
    case "X":
      return "axis-x";
    case "y":
    case "Y":
      return "axis-y";
    case "z":
    case "Z":
      return "axis-z";
    case "+":
    case "=":
      return "zoom-in";
    case "-":
    case "_":
      return "zoom-out";
    case "0":
      return "zoom-fit";
    case "w":
    case "W":
      return "auto-window";
    case "d":
    case "D":
      return "toggle-3d";
    case "o":
    case "O":
      return "toggle-overlay";
    case "u":
    case "U":
      return "toggle-uncertainty";
    case "n":
    case "N":
      return "next-cell";
    case "?":
      return "help";
  }
  if (/^[1-9]$/.test(k)) return `label-${Number(k)}`;
  return null;
}
