import { describe, expect, it } from "vitest";
import { Advisor, DEFAULT_DONE_WHEN, doneBy, loadDoneWhen, saveDoneWhen, type AdviceState } from "../src/advice";
import { Api, type Advice } from "../src/api";

const advice = (gains: number[]): Advice => ({
  axis: "z",
  drawn: [2, 20],
  suggestions: gains.map((g, n) => ({ slice: 11 + n, gain_voxels: g * 1000, dice_gain: g, between: [2, 20] })),
  predicted_dice: 0.9,
  volume_voxels: 500,
});

/** A Storage over a Map. */
function memoryStorage(): Storage {
  const m = new Map<string, string>();
  return {
    getItem: (k) => m.get(k) ?? null,
    setItem: (k, v) => void m.set(k, v),
    removeItem: (k) => void m.delete(k),
    clear: () => m.clear(),
    key: (n) => [...m.keys()][n] ?? null,
    get length() {
      return m.size;
    },
  };
}

describe("the done-when hint", () => {
  it("is done when the best slice adds less than the threshold", () => {
    expect(doneBy(advice([0.02, 0.01]), 0.005)).toBe(false);
    expect(doneBy(advice([0.004, 0.001]), 0.005)).toBe(true);
    expect(doneBy(advice([]), 0.005)).toBe(true);
    // A cap suggested first with a small gain does not end the tracing.
    expect(doneBy(advice([0.001, 0.02]), 0.005)).toBe(false);
    // 0 turns the hint off.
    expect(doneBy(advice([0.0001]), 0)).toBe(false);
  });

  it("keeps the threshold, and falls back to the default for anything odd", () => {
    const s = memoryStorage();
    expect(loadDoneWhen(s)).toBe(DEFAULT_DONE_WHEN);
    saveDoneWhen(s, 0.01);
    expect(loadDoneWhen(s)).toBe(0.01);
    saveDoneWhen(s, 0);
    expect(loadDoneWhen(s)).toBe(0);
    for (const bad of ["-1", "2", "abc"]) {
      s.setItem("interslice.doneWhen", bad);
      expect(loadDoneWhen(s)).toBe(DEFAULT_DONE_WHEN);
    }
  });
});

describe("the advisor", () => {
  it("asks for the target's advice, coalesces refreshes and answers the next slice only for its target", async () => {
    const urls: string[] = [];
    let release: () => void = () => {};
    const gate = new Promise<void>((r) => (release = r));
    const fetcher = (async (url: string) => {
      urls.push(String(url));
      await gate;
      return new Response(JSON.stringify(advice([0.03])), { headers: { "Content-Type": "application/json" } });
    }) as typeof fetch;
    const shown: AdviceState[] = [];
    const a = new Advisor(new Api("", fetcher), "cell_1", {
      target: () => ({ label: 2, axis: "z", method: "" }),
      show: (s) => shown.push(s),
    });
    a.refresh();
    a.refresh();
    a.refresh();
    expect(a.idle).toBe(false);
    release();
    for (let n = 0; n < 50 && !a.idle; n++) await new Promise((r) => setTimeout(r, 1));
    // One request running, one more asked for meanwhile: two in all.
    expect(urls).toEqual([
      "/api/cells/cell_1/advice?label=2&axis=z&count=3",
      "/api/cells/cell_1/advice?label=2&axis=z&count=3",
    ]);
    expect(shown.length).toBe(2);
    expect(a.next(2, "z")).toBe(11);
    expect(a.next(2, "x")).toBeNull();
    expect(a.next(1, "z")).toBeNull();
  });

  it("shows why there is no advice", async () => {
    const fetcher = (() =>
      Promise.resolve(
        new Response(JSON.stringify({ error: "advice needs at least two drawn slices along z, got 1" }), {
          status: 400,
          headers: { "Content-Type": "application/json" },
        }),
      )) as typeof fetch;
    const shown: AdviceState[] = [];
    const a = new Advisor(new Api("", fetcher), "c", {
      target: () => ({ label: 1, axis: "z", method: "" }),
      show: (s) => shown.push(s),
    });
    a.refresh();
    for (let n = 0; n < 50 && !a.idle; n++) await new Promise((r) => setTimeout(r, 1));
    expect(shown[0]).toEqual({ kind: "none", reason: "advice needs at least two drawn slices along z, got 1" });
    expect(a.next(1, "z")).toBeNull();
  });
});
