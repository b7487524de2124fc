import { describe, expect, it } from "vitest";
import {
  StrokeRecorder,
  closureIndex,
  samplesOf,
  signedArea2,
  toContour,
  type PointerLike,
  type Sample,
} from "../src/stroke";

function circle(n: number, r: number, cx = 50, cy = 50, from = 0, to = 2 * Math.PI): Sample[] {
  const out: Sample[] = [];
  for (let i = 0; i <= n; i++) {
    const a = from + ((to - from) * i) / n;
    out.push({ u: cx + r * Math.cos(a), v: cy + r * Math.sin(a), p: 0.3 + (i % 5) / 10, t: 1000 + i * 4 });
  }
  return out;
}

describe("stroke handling", () => {
  it("a stroke that returns to its start closes on pen lift", () => {
    const rec = new StrokeRecorder(2);
    const s = circle(64, 20);
    rec.penDown(s[0], "pen");
    rec.penMove(s.slice(1, -1));
    const r = rec.penUp(s[s.length - 1]);
    expect(r.kind).toBe("closed");
    if (r.kind !== "closed") return;
    // The final sample equals the start and is dropped: 64 distinct points.
    expect(r.contour.points.length).toBe(64);
    expect(r.contour.pressure?.length).toBe(64);
    expect(r.contour.times_ms?.[0]).toBe(0);
    expect(r.contour.times_ms?.[63]).toBe(63 * 4);
    expect(r.contour.tool).toBe("pen");
    // Area close to pi r^2.
    expect(Math.abs(signedArea2(r.contour.points) / 2)).toBeGreaterThan(0.99 * Math.PI * 400 * (1 - 0.01));
    expect(rec.pending).toBe(false);
  });

  it("an open stroke stays pending; pen down again restarts it", () => {
    const rec = new StrokeRecorder(2);
    const a = circle(30, 20, 50, 50, 0, Math.PI);
    rec.penDown(a[0], "pen");
    rec.penMove(a.slice(1));
    expect(rec.penUp().kind).toBe("open");
    expect(rec.pending).toBe(true);
    expect(rec.current.length).toBe(31);
    // Second attempt: the first one is discarded.
    const b = circle(10, 5, 10, 10, 0, Math.PI);
    rec.penDown(b[0], "mouse");
    rec.penMove(b.slice(1));
    rec.penUp();
    expect(rec.current.length).toBe(11);
    expect(rec.current[0].u).toBeCloseTo(15);
    // Add contour closes it.
    const c = rec.finish();
    expect(c?.points.length).toBe(11);
    expect(c?.pressure).toBeUndefined(); // not a pen
    expect(rec.pending).toBe(false);
  });

  it("an overshoot past the start is trimmed at the closest approach", () => {
    const s = circle(100, 20, 50, 50, 0, 2.2 * Math.PI);
    const ci = closureIndex(s, 1.5);
    // Sample 91 is at angle 2.0*pi*... the closest to the start is index round(100/1.1)=91.
    expect(ci).toBe(91);
    const rec = new StrokeRecorder(1.5);
    rec.penDown(s[0], "pen");
    rec.penMove(s.slice(1));
    const r = rec.penUp();
    expect(r.kind).toBe("closed");
    if (r.kind === "closed") expect(r.contour.points.length).toBe(92);
  });

  it("a short wiggle near the start is not a closed path", () => {
    const s: Sample[] = [0, 1, 2, 1, 0].map((d, i) => ({ u: 10 + d * 0.5, v: 10, p: 0.5, t: i }));
    expect(closureIndex(s, 2)).toBe(-1);
  });

  it("degenerate contours are rejected", () => {
    const line: Sample[] = [0, 1, 2, 3].map((d) => ({ u: d, v: d, p: 0.5, t: d }));
    expect(toContour(line, "mouse")).toBeNull();
    expect(toContour(line.slice(0, 2), "mouse")).toBeNull();
    const rec = new StrokeRecorder();
    expect(rec.finish()).toBeNull();
    expect(rec.penUp().kind).toBe("none");
  });

  it("duplicate samples are dropped, keeping the later pressure", () => {
    const rec = new StrokeRecorder();
    rec.penDown({ u: 1, v: 1, p: 0.1, t: 0 }, "pen");
    rec.penMove([
      { u: 1, v: 1, p: 0.4, t: 1 },
      { u: 2, v: 1, p: 0.5, t: 2 },
      { u: NaN, v: 1, p: 0.5, t: 3 },
    ]);
    expect(rec.current.map((s) => [s.u, s.p])).toEqual([
      [1, 0.4],
      [2, 0.5],
    ]);
  });

  it("samplesOf uses every coalesced event", () => {
    const mk = (x: number, y: number, p: number, t: number): PointerLike => ({
      clientX: x,
      clientY: y,
      pressure: p,
      timeStamp: t,
      pointerType: "pen",
    });
    const ev: PointerLike = {
      ...mk(30, 30, 0.9, 30),
      getCoalescedEvents: () => [mk(10, 10, 0.2, 10), mk(20, 20, 0.5, 20), mk(30, 30, 0.9, 30)],
    };
    const s = samplesOf(ev, (x, y) => [x / 10, y / 10]);
    expect(s).toEqual([
      { u: 1, v: 1, p: 0.2, t: 10 },
      { u: 2, v: 2, p: 0.5, t: 20 },
      { u: 3, v: 3, p: 0.9, t: 30 },
    ]);
    // No coalesced list (or an empty one): the event itself; mice get pressure 0.5.
    const m: PointerLike = { ...mk(5, 5, 0, 1), pointerType: "mouse", getCoalescedEvents: () => [] };
    expect(samplesOf(m, (x, y) => [x, y])).toEqual([{ u: 5, v: 5, p: 0.5, t: 1 }]);
  });
});
