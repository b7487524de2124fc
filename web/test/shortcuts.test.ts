import { describe, expect, it } from "vitest";
import { SHORTCUTS, actionOf } from "../src/shortcuts";

const key = (
  k: string,
  m: Partial<{ ctrlKey: boolean; shiftKey: boolean; metaKey: boolean; altKey: boolean }> = {},
) => ({
  key: k,
  ctrlKey: false,
  shiftKey: false,
  metaKey: false,
  altKey: false,
  ...m,
});

describe("shortcuts", () => {
  it("maps keys to actions", () => {
    expect(actionOf(key("ArrowRight"))).toBe("next-slice");
    expect(actionOf(key("ArrowRight", { shiftKey: true }))).toBe("next-slice-1");
    expect(actionOf(key("z", { ctrlKey: true }))).toBe("undo");
    expect(actionOf(key("Z", { ctrlKey: true, shiftKey: true }))).toBe("redo");
    expect(actionOf(key("y", { metaKey: true }))).toBe("redo");
    expect(actionOf(key("z"))).toBe("axis-z");
    expect(actionOf(key("3"))).toBe("label-3");
    expect(actionOf(key("Enter"))).toBe("add-contour");
    expect(actionOf(key("u"))).toBe("toggle-uncertainty");
    expect(actionOf(key("q"))).toBeNull();
    expect(actionOf(key("s", { ctrlKey: true }))).toBeNull();
  });
  it("every help entry's action is reachable from some key", () => {
    const reachable = new Set<string>();
    const keys = [
      "ArrowRight",
      "ArrowLeft",
      "ArrowUp",
      "ArrowDown",
      "PageDown",
      "PageUp",
      "Enter",
      "Escape",
      "c",
      "e",
      "i",
      "g",
      "x",
      "y",
      "z",
      "1",
      "+",
      "-",
      "0",
      "w",
      "d",
      "o",
      "u",
      "n",
      "?",
    ];
    for (const k of keys)
      for (const shift of [false, true]) reachable.add(String(actionOf(key(k, { shiftKey: shift }))));
    reachable.add(String(actionOf(key("z", { ctrlKey: true }))));
    reachable.add(String(actionOf(key("y", { ctrlKey: true }))));
    for (const s of SHORTCUTS) expect(reachable.has(s.action)).toBe(true);
  });
});
