// A small stand-in for `interslice serve`, for developing the web UI without
// the Rust build: it serves web/dist and a synthetic 16-bit cell through the
// API of docs/API.md, keeping everything in memory. The interpolation preview
// it returns copies the nearest drawn contour (the real server interpolates).
//
//   node e2e/mock-server.mjs --dir /tmp/mock --port 8090
//
// It writes DIR/ground_truth/cell_001.nii.gz (labels: 1 cell, 2 nucleus) like
// `interslice demo`, so the end-to-end test can run against either.
import http from "node:http";
import fs from "node:fs";
import path from "node:path";
import zlib from "node:zlib";
import { fileURLToPath } from "node:url";

const args = Object.fromEntries(process.argv.slice(2).reduce((a, v, i, arr) => (v.startsWith("--") ? [...a, [v.slice(2), arr[i + 1]]] : a), []));
const port = Number(args.port ?? 8090);
const dir = args.dir ?? "/tmp/interslice-mock";
const dist = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../dist");

const [nx, ny, nz] = [96, 96, 60];
const spacing = [0.35, 0.35, 0.35];
const vol = new Uint16Array(nx * ny * nz);
const gt = new Uint8Array(nx * ny * nz);
let seed = 1;
const rnd = () => ((seed = (seed * 1103515245 + 12345) & 0x7fffffff) / 0x7fffffff);
for (let k = 0; k < nz; k++)
  for (let j = 0; j < ny; j++)
    for (let i = 0; i < nx; i++) {
      const p = i + nx * (j + ny * k);
      const c = ((i + 0.5 - 48) / 38) ** 2 + ((j + 0.5 - 48) / 32) ** 2 + ((k + 0.5 - 30) / 24) ** 2;
      const n = ((i + 0.5 - 44) / 17) ** 2 + ((j + 0.5 - 50) / 14) ** 2 + ((k + 0.5 - 30) / 13) ** 2;
      let v = 1200;
      if (c <= 1) (v = 9000), (gt[p] = 1);
      if (n <= 1) (v = 21000), (gt[p] = 2);
      vol[p] = Math.max(0, Math.round(v + (rnd() - 0.5) * 3000));
    }

function niftiGz(data, dims, sp) {
  const hdr = Buffer.alloc(352);
  hdr.writeInt32LE(348, 0);
  hdr.writeInt16LE(3, 40);
  dims.forEach((d, i) => hdr.writeInt16LE(d, 42 + 2 * i));
  for (let i = 3; i < 7; i++) hdr.writeInt16LE(1, 42 + 2 * (i + 1));
  hdr.writeInt16LE(2, 70); // uint8
  hdr.writeInt16LE(8, 72);
  hdr.writeFloatLE(1, 76);
  sp.forEach((s, i) => hdr.writeFloatLE(s, 80 + 4 * i));
  hdr.writeFloatLE(352, 108);
  hdr.writeFloatLE(1, 112);
  hdr.write("n+1\0", 344, "latin1");
  return zlib.gzipSync(Buffer.concat([hdr, Buffer.from(data.buffer)]));
}
fs.mkdirSync(path.join(dir, "ground_truth"), { recursive: true });
fs.writeFileSync(path.join(dir, "ground_truth", "cell_001.nii.gz"), niftiGz(gt, [nx, ny, nz], spacing));

const labels = [
  { id: 1, name: "Cell", color: "#e6194b" },
  { id: 2, name: "Nucleus", color: "#3cb44b" },
  { id: 3, name: "Nucleolus 1", color: "#4363d8" },
  { id: 4, name: "Nucleolus 2", color: "#f58231" },
];
const cellMeta = () => [
  { id: "cell_001", name: "cell_001", dims: [nx, ny, nz], spacing, unit: "µm", dtype: "u16", status: status.get("cell_001") ?? "not_started" },
  { id: "cell_002", name: "cell_002", dims: [nx, ny, nz], spacing, unit: "µm", dtype: "u16", status: status.get("cell_002") ?? "not_started" },
];
const status = new Map();
let contours = [];
let nextId = 1;
const byClient = new Map();
const history = [];
const redo = [];
const emptySlices = new Set();
const sessions = new Map();
const segs = [];
const ratings = [];

function sliceOf(axis, index) {
  const [w, h] = axis === "z" ? [nx, ny] : axis === "y" ? [nx, nz] : [ny, nz];
  const out = Buffer.alloc(w * h * 2);
  for (let v = 0; v < h; v++)
    for (let u = 0; u < w; u++) {
      const [i, j, k] = axis === "z" ? [u, v, index] : axis === "y" ? [u, index, v] : [index, u, v];
      out.writeUInt16LE(vol[i + nx * (j + ny * k)], 2 * (u + w * v));
    }
  return { w, h, out };
}

const send = (res, code, body, headers = {}) => {
  if (body instanceof Buffer) {
    res.writeHead(code, { "Content-Type": "application/octet-stream", ...headers });
    return res.end(body);
  }
  res.writeHead(code, { "Content-Type": "application/json", ...headers });
  res.end(body === undefined ? "" : JSON.stringify(body));
};

function user(req) {
  const m = /interslice_session=([^;]+)/.exec(req.headers.cookie ?? "");
  return m ? sessions.get(m[1]) : undefined;
}

function snapshot() {
  return JSON.stringify({ contours, empty: [...emptySlices] });
}
function restore(s) {
  const o = JSON.parse(s);
  contours = o.contours;
  emptySlices.clear();
  o.empty.forEach((e) => emptySlices.add(e));
}
function change(fn) {
  history.push(snapshot());
  redo.length = 0;
  fn();
}

const server = http.createServer(async (req, res) => {
  const url = new URL(req.url, "http://x");
  const p = url.pathname;
  let body = "";
  for await (const c of req) body += c;
  const json = body ? JSON.parse(body) : {};
  if (!p.startsWith("/api/")) {
    let f = path.join(dist, p === "/" ? "index.html" : p);
    if (!f.startsWith(dist) || !fs.existsSync(f)) f = path.join(dist, "index.html");
    const type = f.endsWith(".js") ? "text/javascript" : f.endsWith(".css") ? "text/css" : "text/html";
    res.writeHead(200, { "Content-Type": type });
    return res.end(fs.readFileSync(f));
  }
  if (p === "/api/login" && req.method === "POST") {
    const sid = Math.random().toString(36).slice(2);
    sessions.set(sid, json.name);
    return send(res, 200, { name: json.name, role: "tracer" }, { "Set-Cookie": `interslice_session=${sid}; Path=/; HttpOnly` });
  }
  const me = user(req);
  if (!me) return send(res, 401, { error: "not signed in", auth_required: false });
  if (p === "/api/me") return send(res, 200, { name: me, role: "tracer", auth_required: false });
  if (p === "/api/logout") return send(res, 204);
  if (p === "/api/labels") {
    if (req.method === "POST") {
      const l = { id: labels.length + 1, name: json.name, color: json.color ?? "#911eb4" };
      labels.push(l);
      return send(res, 201, l);
    }
    return send(res, 200, labels);
  }
  if (p === "/api/methods") return send(res, 200, [{ name: "linear", description: "contour correspondence" }, { name: "sdf", description: "signed distance" }]);
  if (p === "/api/cells") return send(res, 200, cellMeta().filter((c) => url.searchParams.get("queue") !== "true" || c.status !== "done"));
  const m = /^\/api\/cells\/([^/]+)(\/.*)?$/.exec(p);
  if (!m) return send(res, 404, { error: "unknown" });
  const cell = m[1];
  const rest = m[2] ?? "";
  const meta = cellMeta().find((c) => c.id === cell);
  if (!meta) return send(res, 404, { error: "unknown cell" });
  if (rest === "") return send(res, 200, { ...meta, min: 0, max: 65535, labels });
  if (rest === "/status") {
    status.set(cell, json.status);
    return send(res, 200, { status: json.status });
  }
  if (rest === "/histogram") {
    const counts = new Array(256).fill(0);
    for (const v of vol) counts[v >> 8]++;
    return send(res, 200, { min: 0, max: 65535, bin_width: 256, counts });
  }
  if (rest === "/time") return send(res, 200, { total_seconds: json.seconds ?? 0 });
  let s = /^\/slices\/([xyz])\/(\d+)$/.exec(rest);
  if (s) {
    const { w, h, out } = sliceOf(s[1], Number(s[2]));
    return send(res, 200, out, { "X-Width": w, "X-Height": h, "X-Dtype": "u16" });
  }
  const mine = () => contours.filter((c) => c.cell === cell && c.author === me);
  if (rest === "/contours" && req.method === "GET") return send(res, 200, mine());
  if (rest === "/contours" && req.method === "POST") {
    if (json.client_id && byClient.has(json.client_id)) return send(res, 201, byClient.get(json.client_id));
    const c = { ...json, id: nextId++, cell, author: me, created: new Date().toISOString() };
    change(() => {
      contours.push(c);
      emptySlices.delete(`${cell}/${json.label}/${json.axis}/${json.index}`);
    });
    if (json.client_id) byClient.set(json.client_id, c);
    return send(res, 201, c);
  }
  s = /^\/slices\/([xyz])\/(\d+)\/(contours|empty)$/.exec(rest);
  if (s) {
    const [axis, index] = [s[1], Number(s[2])];
    change(() => {
      contours = contours.filter((c) => !(c.cell === cell && c.author === me && c.axis === axis && c.index === index && c.label === json.label));
      if (s[3] === "empty") emptySlices.add(`${cell}/${json.label}/${axis}/${index}`);
      else (json.contours ?? []).forEach((c) => contours.push({ ...c, label: json.label, axis, index, id: nextId++, cell, author: me }));
    });
    return send(res, 200, {});
  }
  if (rest.startsWith("/drawn")) {
    const label = Number(url.searchParams.get("label"));
    const axis = url.searchParams.get("axis");
    const idx = new Map();
    mine().filter((c) => c.label === label && c.axis === axis).forEach((c) => idx.set(c.index, false));
    for (const e of emptySlices) {
      const [c, l, a, i] = e.split("/");
      if (c === cell && Number(l) === label && a === axis) idx.set(Number(i), true);
    }
    return send(res, 200, [...idx].map(([index, empty]) => ({ index, empty })).sort((a, b) => a.index - b.index));
  }
  if (rest === "/undo" || rest === "/redo") {
    const [from, to] = rest === "/undo" ? [history, redo] : [redo, history];
    if (!from.length) return send(res, 200, { changed: false });
    to.push(snapshot());
    restore(from.pop());
    return send(res, 200, { changed: true });
  }
  if (rest === "/interpolate") {
    const { label, axis } = json;
    const depth = axis === "z" ? nz : axis === "y" ? ny : nx;
    const drawn = mine().filter((c) => c.label === label && c.axis === axis);
    const idxs = [...new Set(drawn.map((c) => c.index))].sort((a, b) => a - b);
    const slices = [];
    for (let i = 0; i < depth && idxs.length; i++) {
      if (i < idxs[0] || i > idxs[idxs.length - 1]) continue;
      const near = idxs.reduce((a, b) => (Math.abs(b - i) < Math.abs(a - i) ? b : a));
      slices.push({ index: i, drawn: idxs.includes(i), contours: drawn.filter((c) => c.index === near).map((c) => c.points) });
    }
    return send(res, 200, { result_id: `r${nextId++}`, method: json.method ?? "linear", label, axis, slices, volume: 1234.5, unit: "µm" });
  }
  if (/^\/results\/[^/]+\/mesh$/.test(rest)) {
    // An octahedron scaled to the nucleus.
    const v = [10, 0, 0, -10, 0, 0, 0, 8, 0, 0, -8, 0, 0, 0, 6, 0, 0, -6].map((x, i) => x * spacing[i % 3] * 2);
    return send(res, 200, { vertices: v, indices: [0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5] });
  }
  if (rest === "/segmentations") {
    if (req.method === "POST") {
      const sg = { id: `seg${segs.length + 1}`, name: `${json.method}`, method: json.method, params: json, created: new Date().toISOString() };
      segs.push(sg);
      return send(res, 201, sg);
    }
    return send(res, 200, segs);
  }
  if (rest === "/evaluate") return send(res, 200, { tp: 9000, fp: 800, fn: 500, tn: 500000, dice: 0.9326, jaccard: 0.8738, sensitivity: 0.9474, specificity: 0.9984, precision: 0.9184, volume_similarity: 0.9839, volume_gt: 408.3, volume_seg: 420.1, hd: 2.1, hd95: 1.05, assd: 0.41, nsd: 0.93 });
  s = /^\/overlay\/([xyz])\/(\d+)$/.exec(rest);
  if (s) {
    const { w, h } = sliceOf(s[1], Number(s[2]));
    const o = Buffer.alloc(w * h);
    for (let v = 0; v < h; v++) for (let u = 0; u < w; u++) {
      const d = ((u - 44) / 17) ** 2 + ((v - 50) / 14) ** 2;
      o[u + w * v] = d < 0.8 ? 1 : d < 1 ? 3 : d < 1.15 ? 2 : 0;
    }
    return send(res, 200, o);
  }
  if (rest === "/ratings") {
    if (req.method === "POST") {
      const r = { ...json, user: me, created: new Date().toISOString() };
      ratings.push(r);
      return send(res, 201, r);
    }
    return send(res, 200, ratings);
  }
  return send(res, 404, { error: `unknown path ${p}` });
});
server.listen(port, "127.0.0.1", () => console.log(`mock server on http://127.0.0.1:${port} (dir ${dir})`));
process.on("SIGTERM", () => server.close(() => process.exit(0)));
