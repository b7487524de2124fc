//! The concurrency test: many clients tracing different cells and slices at
//! once over loopback HTTP, then a check of the database against what every
//! client was told.
//!
//! Each client signs in as its own user, works on one cell and its own set
//! of slices, and keeps a model of what it believes is stored: contours it
//! added (answered 201), slices it replaced (answered 200) and contours it
//! deleted (answered 204). Reads of its own slices are checked against that
//! model while the test runs. Afterwards the database is read directly: a
//! contour in a model but not in the database is *lost*; a contour in one
//! user's rows that another client's model holds is *crossed*; any other row
//! nobody was told about is *unexpected*. A correct server has zero of each.
//!
//! With a preload ([`run_preloaded`]) every client first replaces one of its
//! slices with that many contours and keeps tracing on it: the cost of a
//! write must not depend on how much the slice holds. The report ends with
//! the space the database takes (all pages, the `contours` table, the WAL).
use crate::client::{Client, quantile};
use anyhow::{Context as _, bail};
use interslice_core::{AnyVolume, Geometry, LengthUnit, Volume};
use interslice_server::{Config, RunningServer};
use interslice_store::{ContourQuery, SpaceUsage};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::{Arc, Barrier};
use std::time::{Duration, Instant};

/// How the load test runs.
#[derive(Debug, Clone)]
pub struct LoadConfig {
    /// Concurrent clients, one user each.
    pub clients: usize,
    /// How long they trace.
    pub duration: Duration,
    /// Cells in the project (clients are spread over them).
    pub cells: usize,
    /// Voxels per side of each (cubic, 8-bit) cell.
    pub size: usize,
}

impl Default for LoadConfig {
    /// 20 clients for 60 s on 4 cells of 64³.
    fn default() -> LoadConfig {
        LoadConfig {
            clients: 20,
            duration: Duration::from_secs(60),
            cells: 4,
            size: 64,
        }
    }
}

/// Latencies of one kind of request.
#[derive(Debug, Clone)]
pub struct OpStats {
    /// "add", "replace", "delete", "slice" or "read".
    pub op: &'static str,
    /// Requests made.
    pub count: usize,
    /// Median latency, ms.
    pub p50_ms: f64,
    /// 99th percentile latency, ms.
    pub p99_ms: f64,
}

/// What the load test measured and found.
#[derive(Debug, Clone)]
pub struct LoadReport {
    /// Requests answered (any status).
    pub requests: usize,
    /// Writes answered 2xx.
    pub acknowledged_writes: usize,
    /// Wall time of the tracing phase, s.
    pub seconds: f64,
    /// Median latency of all requests, ms.
    pub p50_ms: f64,
    /// 99th percentile latency of all requests, ms.
    pub p99_ms: f64,
    /// Per kind of request.
    pub ops: Vec<OpStats>,
    /// Acknowledged contours missing from the database (or changed).
    pub lost: usize,
    /// Contours stored under a user other than the one who wrote them.
    pub crossed: usize,
    /// Rows nobody was told about.
    pub unexpected: usize,
    /// Reads during the run that disagreed with the client's model.
    pub read_mismatches: usize,
    /// Non-2xx answers and transport errors (first few messages kept).
    pub errors: usize,
    /// The first error messages.
    pub error_samples: Vec<String>,
    /// `PRAGMA integrity_check` afterwards.
    pub integrity: String,
    /// Contours preloaded per client.
    pub preload: usize,
    /// Contours stored at the end (all users).
    pub live_contours: usize,
    /// The space the database takes at the end.
    pub space: SpaceUsage,
}

impl LoadReport {
    /// Requests per second over the tracing phase.
    pub fn requests_per_second(&self) -> f64 {
        self.requests as f64 / self.seconds.max(1e-9)
    }

    /// True when nothing was lost, crossed, unexpected, misread or refused,
    /// and the database is sound.
    pub fn clean(&self) -> bool {
        self.lost == 0
            && self.crossed == 0
            && self.unexpected == 0
            && self.read_mismatches == 0
            && self.errors == 0
            && self.integrity == "ok"
    }
}

impl std::fmt::Display for LoadReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} requests in {:.1} s: {:.0} requests/s, p50 {:.2} ms, p99 {:.2} ms",
            self.requests,
            self.seconds,
            self.requests_per_second(),
            self.p50_ms,
            self.p99_ms
        )?;
        for o in &self.ops {
            writeln!(
                f,
                "  {:<8} {:>7} requests  p50 {:>6.2} ms  p99 {:>6.2} ms",
                o.op, o.count, o.p50_ms, o.p99_ms
            )?;
        }
        writeln!(
            f,
            "acknowledged writes {}; lost {}, crossed {}, unexpected {}, read mismatches {}, errors {}; integrity_check: {}",
            self.acknowledged_writes,
            self.lost,
            self.crossed,
            self.unexpected,
            self.read_mismatches,
            self.errors,
            self.integrity
        )?;
        for e in &self.error_samples {
            writeln!(f, "  error: {e}")?;
        }
        let mb = |b: u64| b as f64 / (1 << 20) as f64;
        writeln!(
            f,
            "{} live contours ({} preloaded per client); database {:.1} MiB, contours table {:.2} MiB ({:.1}×), WAL {:.1} MiB",
            self.live_contours,
            self.preload,
            mb(self.space.database_bytes),
            mb(self.space.contours_bytes),
            self.space.database_bytes as f64 / self.space.contours_bytes.max(1) as f64,
            mb(self.space.wal_bytes)
        )?;
        for (name, bytes) in self.space.by_object.iter().take(8) {
            writeln!(f, "  {name}: {:.2} MiB", mb(*bytes))?;
        }
        Ok(())
    }
}

/// Write `count` synthetic cells `cell_NN.nii` of `dims` into `dir` (a
/// gradient with a bright ball, so slices differ); 16-bit when `wide`.
pub fn write_cells(dir: &Path, count: usize, dims: [usize; 3], wide: bool) -> anyhow::Result<()> {
    let g = Geometry::new(dims, [0.35; 3], LengthUnit::Micrometre)?;
    let [nx, ny, nz] = dims;
    let value = |i: usize, j: usize, k: usize| -> f64 {
        let (x, y, z) = (
            i as f64 / nx as f64 - 0.5,
            j as f64 / ny as f64 - 0.5,
            k as f64 / nz.max(2) as f64 - 0.5,
        );
        let ball = if x * x + y * y + z * z < 0.09 {
            0.6
        } else {
            0.0
        };
        (0.2 + 0.2 * (x + y) + ball).clamp(0.0, 1.0)
    };
    for n in 1..=count {
        let mut v8 = Vec::new();
        let mut v16 = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let x = value(i, j, k) * (0.9 + 0.02 * n as f64);
                    if wide {
                        v16.push((x * 60000.0) as u16);
                    } else {
                        v8.push((x * 250.0) as u8);
                    }
                }
            }
        }
        let vol = if wide {
            AnyVolume::U16(Volume::from_vec(g.clone(), v16)?)
        } else {
            AnyVolume::U8(Volume::from_vec(g.clone(), v8)?)
        };
        let path = dir.join(format!("cell_{n:02}.nii"));
        interslice_io::write_volume(&path, &vol)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// What a client believes is stored: slice (label, index) → contour id → points.
type Model = BTreeMap<(u16, usize), BTreeMap<i64, Vec<[f64; 2]>>>;

struct ClientResult {
    user: String,
    cell: String,
    model: Model,
    latencies: Vec<(&'static str, f64)>,
    acknowledged: usize,
    read_mismatches: usize,
    errors: usize,
    error_samples: Vec<String>,
}

/// Points of a traced outline: a pen stroke as the web UI sends it
/// ([`STROKE_POINTS`] points at full `f64` precision) around the circle
/// inscribed in the square with corner (`x0`, `y0`) and side `side`. Real
/// strokes, not 4-corner squares, so that the space figures weigh history
/// against tracing as a lab's database does.
fn stroke(x0: f64, y0: f64, side: f64) -> Vec<[f64; 2]> {
    let r = side / 2.0;
    (0..STROKE_POINTS)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / STROKE_POINTS as f64;
            [x0 + r + r * a.cos(), y0 + r + r * a.sin()]
        })
        .collect()
}

/// Points per traced outline in the load test (a nucleus traced with a pen
/// and smoothed is 50-200 points).
const STROKE_POINTS: usize = 64;

/// The pen pressure and time stamps of a [`stroke`], as the web UI sends them.
fn pen_samples(seq: u64) -> (Vec<f64>, Vec<f64>) {
    let pressure = (0..STROKE_POINTS)
        .map(|i| 0.3 + 0.4 * ((i as u64 + seq) % 8) as f64 / 8.0)
        .collect();
    let times = (0..STROKE_POINTS).map(|i| i as f64 * 8.333).collect();
    (pressure, times)
}

fn ids_points(v: &serde_json::Value) -> Option<(i64, Vec<[f64; 2]>)> {
    let id = v.get("id")?.as_i64()?;
    let points = serde_json::from_value(v.get("points")?.clone()).ok()?;
    Some((id, points))
}

/// What one client does: sign in, preload its first slice, wait for every
/// other client at `start`, then trace for `duration`.
struct Plan {
    n: usize,
    cell: String,
    slices: Vec<usize>,
    size: usize,
    preload: usize,
    start: Arc<Barrier>,
    duration: Duration,
}

fn trace(base: &str, plan: Plan) -> ClientResult {
    let Plan {
        n,
        ref cell,
        ref slices,
        size,
        preload,
        ref start,
        duration,
    } = plan;
    let user = format!("tracer-{n:02}");
    let mut r = ClientResult {
        user: user.clone(),
        cell: cell.to_string(),
        model: Model::new(),
        latencies: Vec::new(),
        acknowledged: 0,
        read_mismatches: 0,
        errors: 0,
        error_samples: Vec::new(),
    };
    let fail = |r: &mut ClientResult, what: String| {
        r.errors += 1;
        if r.error_samples.len() < 3 {
            r.error_samples.push(format!("{user}: {what}"));
        }
    };
    let mut client = Client::new(base);
    let signed_in = match client.login(&user, None) {
        Ok(a) if a.ok() => true,
        Ok(a) => {
            fail(&mut r, format!("login: {} {:?}", a.status, a.error()));
            false
        }
        Err(e) => {
            fail(&mut r, format!("login: {e}"));
            false
        }
    };
    let room = (size as f64 - 6.0).max(1.0);
    // The preloaded slice: label 1 on the first slice, never replaced.
    let big = (1u16, slices[0]);
    if signed_in && preload > 0 {
        let cs: Vec<serde_json::Value> = (0..preload)
            .map(|i| {
                let x = 1.0 + (i % (room as usize * 4)) as f64 * 0.25;
                serde_json::json!({"points": stroke(x, x, 2.0)})
            })
            .collect();
        let answer = client.json(
            "PUT",
            &format!("/api/cells/{cell}/slices/z/{}/contours", big.1),
            &serde_json::json!({"label": big.0, "contours": cs}),
        );
        let stored: Option<BTreeMap<i64, Vec<[f64; 2]>>> =
            answer.ok().filter(|a| a.ok()).and_then(|a| {
                a.json()
                    .as_array()
                    .map(|l| l.iter().filter_map(ids_points).collect())
            });
        match stored {
            Some(s) if s.len() == preload => {
                r.model.insert(big, s);
            }
            _ => fail(&mut r, "preload: not answered with the contours".into()),
        }
    }
    let preloaded = r.model.get(&big).map_or(0, |m| m.len());
    start.wait();
    if !signed_in {
        return r;
    }
    let deadline = Instant::now() + duration;
    let contours = format!("/api/cells/{cell}/contours");
    let mut seq: u64 = 0;
    while Instant::now() < deadline {
        seq += 1;
        let slice = slices[(seq as usize / 7) % slices.len()];
        let label = 1 + (seq % 2) as u16;
        let key = (label, slice);
        // Corners on a 0.25 grid inside the slice.
        let x0 = 1.0 + ((seq * 7) % (room as u64 * 4)) as f64 * 0.25;
        let y0 = 1.0 + ((seq * 13) % (room as u64 * 4)) as f64 * 0.25;
        // A tracer keeps a few contours per label and slice: a slice that has
        // three gets one deleted instead of a fourth added.
        // The preloaded contours stay: they do not count, and the slice is
        // added to instead of replaced.
        let kept = if key == big { preloaded } else { 0 };
        let on_slice = r.model.get(&key).map_or(0, |m| m.len()) - kept;
        let op = match seq % 10 {
            0..=5 if on_slice >= 3 => "delete",
            0..=5 => "add",
            6 if key == big && on_slice >= 3 => "delete",
            6 if key == big => "add",
            6 => "replace",
            7 if on_slice > 0 => "delete",
            7 => "add",
            8 => "slice",
            _ => "read",
        };
        let t = Instant::now();
        let answer = match op {
            "add" => {
                let (pressure, times_ms) = pen_samples(seq);
                client.json(
                    "POST",
                    &contours,
                    &serde_json::json!({
                        "label": label, "axis": "z", "index": slice,
                        "points": stroke(x0, y0, 4.0), "pressure": pressure,
                        "times_ms": times_ms, "tool": "loadtest",
                        "client_id": format!("{user}-{seq}"),
                    }),
                )
            }
            "replace" => client.json(
                "PUT",
                &format!("/api/cells/{cell}/slices/z/{slice}/contours"),
                &serde_json::json!({"label": label, "contours": [
                    {"points": stroke(x0, y0, 3.0)}, {"points": stroke(x0 + 0.5, y0, 2.0)}
                ]}),
            ),
            "delete" => {
                // The slice's newest contour (the op is only chosen when there is one).
                let id = r.model[&key]
                    .keys()
                    .next_back()
                    .copied()
                    .unwrap_or_default();
                client.delete(&format!("{contours}/{id}"))
            }
            "slice" => client.get(&format!("/api/cells/{cell}/slices/z/{slice}")),
            _ => client.get(&format!("{contours}?axis=z&index={slice}&label={label}")),
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let a = match answer {
            Ok(a) => a,
            Err(e) => {
                fail(&mut r, format!("{op}: {e}"));
                continue;
            }
        };
        r.latencies.push((op, ms));
        if !a.ok() {
            fail(&mut r, format!("{op}: {} {:?}", a.status, a.error()));
            continue;
        }
        match op {
            "add" => match ids_points(&a.json()) {
                Some((id, points)) => {
                    r.model.entry(key).or_default().insert(id, points);
                    r.acknowledged += 1;
                }
                None => fail(&mut r, "add: answer without id/points".into()),
            },
            "replace" => {
                let stored: Option<BTreeMap<i64, Vec<[f64; 2]>>> = a
                    .json()
                    .as_array()
                    .map(|l| l.iter().filter_map(ids_points).collect());
                match stored {
                    Some(s) if s.len() == 2 => {
                        r.model.insert(key, s);
                        r.acknowledged += 1;
                    }
                    _ => fail(&mut r, "replace: answer is not two contours".into()),
                }
            }
            "delete" => {
                if let Some(m) = r.model.get_mut(&key) {
                    m.pop_last();
                }
                r.acknowledged += 1;
            }
            "slice" => {
                if a.body.len() != size * size {
                    fail(&mut r, format!("slice: {} bytes", a.body.len()));
                }
            }
            _ => {
                let seen: BTreeMap<i64, Vec<[f64; 2]>> = a
                    .json()
                    .as_array()
                    .map(|l| l.iter().filter_map(ids_points).collect())
                    .unwrap_or_default();
                let expected = r.model.get(&key).cloned().unwrap_or_default();
                if seen != expected {
                    r.read_mismatches += 1;
                }
            }
        }
    }
    r
}

fn stats(op: &'static str, mut ms: Vec<f64>) -> OpStats {
    ms.sort_by(f64::total_cmp);
    OpStats {
        op,
        count: ms.len(),
        p50_ms: quantile(&ms, 0.5).unwrap_or(0.0),
        p99_ms: quantile(&ms, 0.99).unwrap_or(0.0),
    }
}

/// Run the load test on a fresh project in a temporary folder.
pub fn run(cfg: &LoadConfig) -> anyhow::Result<LoadReport> {
    run_preloaded(cfg, 0)
}

/// [`run`], each client first replacing one of its slices with `preload`
/// contours (at most 100000) that stay while it traces on.
pub fn run_preloaded(cfg: &LoadConfig, preload: usize) -> anyhow::Result<LoadReport> {
    if preload > 100_000 {
        bail!("a preload of at most 100000 contours per client");
    }
    if cfg.clients == 0 || cfg.cells == 0 || cfg.size < 16 {
        bail!("need at least one client, one cell and cells of 16³ or more");
    }
    let dir = tempfile::tempdir()?;
    write_cells(dir.path(), cfg.cells, [cfg.size; 3], false)?;
    let mut config = Config::new(dir.path());
    config.bind = std::net::SocketAddr::from(([127, 0, 0, 1], 0));
    let server: RunningServer = interslice_server::spawn(config)?;
    let base = server.url();
    let cell_ids = server.state.cell_ids();
    // Clients sharing a cell take interleaved slices, so no two share one.
    let per_cell = cfg.clients.div_ceil(cfg.cells);
    let barrier = Arc::new(Barrier::new(cfg.clients + 1));
    let handles: Vec<_> = (0..cfg.clients)
        .map(|n| {
            let plan = Plan {
                n,
                cell: cell_ids[n % cell_ids.len()].clone(),
                slices: (0..cfg.size)
                    .filter(|s| s % per_cell == n / cell_ids.len())
                    .collect(),
                size: cfg.size,
                preload,
                start: barrier.clone(),
                duration: cfg.duration,
            };
            let base = base.clone();
            std::thread::spawn(move || trace(&base, plan))
        })
        .collect();
    // Tracing starts when every client has signed in and preloaded.
    barrier.wait();
    let start = Instant::now();
    let results: Vec<ClientResult> = handles
        .into_iter()
        .map(|h| h.join().map_err(|_| anyhow::anyhow!("a client panicked")))
        .collect::<anyhow::Result<_>>()?;
    let seconds = start.elapsed().as_secs_f64();

    // Every contour id any client believes in, and whose it is.
    let mut owner: HashMap<i64, &str> = HashMap::new();
    for r in &results {
        for m in r.model.values() {
            for id in m.keys() {
                owner.insert(*id, &r.user);
            }
        }
    }
    let store = &server.state.store;
    let (mut lost, mut crossed, mut unexpected, mut live_contours) = (0, 0, 0, 0);
    for r in &results {
        let Some(user) = store.user(&r.user)? else {
            continue;
        };
        let rows = store.contours(&ContourQuery {
            cell: r.cell.clone(),
            user_id: user.id,
            ..Default::default()
        })?;
        let mut stored: Model = Model::new();
        live_contours += rows.len();
        for c in rows {
            let contour = c.contour;
            if contour.author != r.user {
                crossed += 1;
            }
            stored
                .entry((contour.label, contour.slice.index))
                .or_default()
                .insert(c.id, contour.points);
        }
        for (key, m) in &r.model {
            for (id, points) in m {
                if stored.get(key).and_then(|s| s.get(id)) != Some(points) {
                    lost += 1;
                }
            }
        }
        for (key, m) in &stored {
            for id in m.keys() {
                if r.model.get(key).is_some_and(|x| x.contains_key(id)) {
                    continue;
                }
                match owner.get(id) {
                    Some(o) if *o != r.user => crossed += 1,
                    _ => unexpected += 1,
                }
            }
        }
    }
    let integrity = store.integrity_check()?;
    let space = store.space()?;

    let mut all = Vec::new();
    let mut by_op: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    for r in &results {
        for &(op, ms) in &r.latencies {
            all.push(ms);
            by_op.entry(op).or_default().push(ms);
        }
    }
    let total = stats("all", all);
    Ok(LoadReport {
        requests: total.count,
        acknowledged_writes: results.iter().map(|r| r.acknowledged).sum(),
        seconds,
        p50_ms: total.p50_ms,
        p99_ms: total.p99_ms,
        ops: by_op.into_iter().map(|(op, v)| stats(op, v)).collect(),
        lost,
        crossed,
        unexpected,
        read_mismatches: results.iter().map(|r| r.read_mismatches).sum(),
        errors: results.iter().map(|r| r.errors).sum(),
        error_samples: results
            .iter()
            .flat_map(|r| r.error_samples.iter().cloned())
            .take(5)
            .collect(),
        integrity,
        preload,
        live_contours,
        space,
    })
}
