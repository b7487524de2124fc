import { describe, expect, it } from "vitest";
import { Api, ApiError, type Contour } from "../src/api";
import { Outbox, applyPending, retryable, type KV, type Op } from "../src/queue";

class MemKV implements KV {
  m = new Map<string, string>();
  getItem(k: string) {
    return this.m.get(k) ?? null;
  }
  setItem(k: string, v: string) {
    this.m.set(k, v);
  }
}

/** A mock server: stores contours by client_id; fails the first `failures` requests. */
function mockFetch(failures: number) {
  const stored = new Map<string, unknown>();
  let calls = 0;
  const answer = (init?: RequestInit): Response => {
    const body = JSON.parse(typeof init?.body === "string" ? init.body : "{}") as {
      client_id?: string;
      label?: number;
    };
    if (body.client_id) {
      if (!stored.has(body.client_id)) stored.set(body.client_id, { ...body, id: stored.size + 1 });
      return new Response(JSON.stringify(stored.get(body.client_id)), { status: 201 });
    }
    if (body.label === 99) return new Response(JSON.stringify({ error: "unknown label" }), { status: 400 });
    return new Response(null, { status: 204 });
  };
  const f = (_url: RequestInfo | URL, init?: RequestInit): Promise<Response> => {
    calls++;
    if (calls <= failures) return Promise.reject(new TypeError("Failed to fetch"));
    return Promise.resolve(answer(init));
  };
  return { f, stored, calls: () => calls };
}

const op = (id: string, index = 5): Op => ({
  kind: "contour",
  cell: "c1",
  client_id: id,
  body: {
    label: 2,
    axis: "z",
    index,
    points: [
      [0, 0],
      [1, 0],
      [0, 1],
    ],
  },
});

describe("outbox", () => {
  it("persists before sending and survives a reload", async () => {
    const kv = new MemKV();
    const m = mockFetch(1000);
    const ob = new Outbox(new Api("", m.f), kv);
    await ob.push(op("a"));
    await ob.push(op("b"));
    expect(ob.pending.length).toBe(2);
    // "Reload": a new outbox over the same storage, with the server back.
    const m2 = mockFetch(0);
    const ob2 = new Outbox(new Api("", m2.f), kv);
    expect(ob2.pending.map((o) => o.client_id)).toEqual(["a", "b"]);
    await ob2.flush();
    expect(ob2.pending.length).toBe(0);
    expect([...m2.stored.keys()]).toEqual(["a", "b"]);
    expect(JSON.parse(kv.getItem("interslice.outbox.v1")!)).toEqual([]);
  });

  it("retries are idempotent through client_id", async () => {
    const kv = new MemKV();
    const m = mockFetch(0);
    const ob = new Outbox(new Api("", m.f), kv);
    await ob.push(op("x"));
    // Answer lost: the same op is sent again.
    await ob.push(op("x"));
    expect(m.stored.size).toBe(1);
  });

  it("drops operations the server rejects and goes on", async () => {
    const kv = new MemKV();
    const m = mockFetch(0);
    const ob = new Outbox(new Api("", m.f), kv);
    const errors: string[] = [];
    ob.onChange = (_n, e) => e && errors.push(e);
    await ob.push({ kind: "empty", cell: "c1", client_id: "e", axis: "z", index: 1, label: 99 });
    await ob.push(op("y"));
    expect(ob.pending.length).toBe(0);
    expect(errors).toEqual(["not saved: unknown label"]);
    expect(m.stored.has("y")).toBe(true);
  });

  it("classifies errors", () => {
    expect(retryable(new TypeError("Failed to fetch"))).toBe(true);
    expect(retryable(new ApiError(503, "busy"))).toBe(true);
    expect(retryable(new ApiError(400, "bad"))).toBe(false);
  });
});

describe("pending changes over server contours", () => {
  const server: Contour[] = [
    {
      id: 1,
      label: 2,
      axis: "z",
      index: 5,
      points: [
        [0, 0],
        [1, 0],
        [0, 1],
      ],
    },
    {
      id: 2,
      label: 1,
      axis: "z",
      index: 5,
      points: [
        [0, 0],
        [2, 0],
        [0, 2],
      ],
    },
  ];
  it("adds, replaces and empties", () => {
    const ops: Op[] = [
      op("n1", 10),
      { kind: "empty", cell: "c1", client_id: "e1", axis: "z", index: 5, label: 2 },
      {
        kind: "replace",
        cell: "c1",
        client_id: "r1",
        axis: "z",
        index: 10,
        label: 2,
        contours: [
          {
            label: 2,
            axis: "z",
            index: 10,
            points: [
              [5, 5],
              [6, 5],
              [5, 6],
            ],
          },
        ],
      },
      op("other", 3),
    ];
    ops[3].cell = "c2";
    const out = applyPending(server, ops, "c1");
    expect(out.map((c) => c.id)).toEqual([2, "r1/0"]);
  });
  it("does not duplicate a contour the server already has", () => {
    const o = op("n1");
    if (o.kind !== "contour") throw new Error("unreachable");
    const s = [...server, { ...o.body, id: "n1" } as Contour];
    expect(applyPending(s, [op("n1")], "c1").length).toBe(3);
  });
});
