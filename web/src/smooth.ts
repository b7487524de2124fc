/**
 * Taubin λ|μ smoothing of a triangle mesh, for display only.
 *
 * The surface of a binary mask has the voxel grid's terraces; shown as is it
 * looks like a stack of coins. Taubin's two-step Laplacian (a shrinking step
 * λ > 0, then an inflating step μ < −λ) removes those terraces without the
 * shrinkage of plain Laplacian smoothing, so the surface stays where the
 * tracing put it (within a fraction of a voxel). The measured volumes and the
 * exported labels never go through this.
 */

/**
 * Smoothed vertex positions (`x, y, z` per vertex) of the mesh `vertices` /
 * `indices`. Vertices at the same position are treated as one, so meshes with
 * duplicated corners smooth the same as welded ones.
 */
export function taubin(
  vertices: ArrayLike<number>,
  indices: ArrayLike<number>,
  iterations = 12,
  lambda = 0.5,
  mu = -0.53,
): Float32Array {
  const n = vertices.length / 3;
  // Weld: one id per distinct position.
  const id = new Int32Array(n);
  const seen = new Map<string, number>();
  const pos: number[] = [];
  for (let v = 0; v < n; v++) {
    const key = `${vertices[3 * v]},${vertices[3 * v + 1]},${vertices[3 * v + 2]}`;
    let w = seen.get(key);
    if (w === undefined) {
      w = pos.length / 3;
      seen.set(key, w);
      pos.push(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]);
    }
    id[v] = w;
  }
  const m = pos.length / 3;
  const nbrs: Set<number>[] = Array.from({ length: m }, () => new Set<number>());
  for (let t = 0; t + 2 < indices.length; t += 3) {
    const a = id[indices[t]];
    const b = id[indices[t + 1]];
    const c = id[indices[t + 2]];
    nbrs[a].add(b).add(c);
    nbrs[b].add(a).add(c);
    nbrs[c].add(a).add(b);
  }
  const lists = nbrs.map((s) => [...s]);
  let cur = Float64Array.from(pos);
  let next = new Float64Array(cur.length);
  for (let it = 0; it < 2 * iterations; it++) {
    const f = it % 2 === 0 ? lambda : mu;
    for (let w = 0; w < m; w++) {
      const l = lists[w];
      for (let d = 0; d < 3; d++) {
        const p = cur[3 * w + d];
        if (l.length === 0) {
          next[3 * w + d] = p;
          continue;
        }
        let s = 0;
        for (const u of l) s += cur[3 * u + d];
        next[3 * w + d] = p + f * (s / l.length - p);
      }
    }
    [cur, next] = [next, cur];
  }
  const out = new Float32Array(3 * n);
  for (let v = 0; v < n; v++) for (let d = 0; d < 3; d++) out[3 * v + d] = cur[3 * id[v] + d];
  return out;
}
