"""interslice against the Python libraries, side by side in one process.

Not a test: prints times (median of --reps runs, wall clock) and the ratio
of each library's time to interslice's, on the same arrays:

* HD95 + mean surface distance on the blob pairs of ``blobs.py`` (256³,
  512³): ``interslice.evaluate`` (every metric) against SimpleITK
  (LabelContour + SignedMaurerDistanceMap, the fastest SimpleITK route to
  HD95), MONAI, medpy and DeepMind's surface-distance;
* overlap only at the same sizes: ``interslice.overlap`` against SimpleITK's
  LabelOverlapMeasuresImageFilter, medpy and MONAI;
* interpolation of a phantom nucleus traced on every 5th z slice (--skip):
  ``interslice.interpolate`` against ITK's morphological contour
  interpolation and a plain scipy signed-distance blend (the approach of the
  existing napari plugins), with the Dice of each against the truth. The
  default method and ITK's are timed in five alternating rounds, each
  after two untimed runs, so that their ratio is taken under the same load
  of the machine (whose speed drifts by a fifth over seconds here).

SimpleITK, ITK, torch (MONAI) and interslice (rayon) get the same number of
threads (--threads, default: every core); numpy, scipy, medpy and
surface-distance run on one. Libraries that are not installed are skipped.
Install the comparison libraries with
``pip install SimpleITK itk-morphologicalcontourinterpolation medpy monai surface-distance scipy``.

    python python/bench/compare.py [--sizes 256,512] [--reps 3] [--threads 2] [--slow] [--cache DIR]
                                   [--only interpolation --phantom 256 --skip 9]
"""

import argparse
import contextlib
import importlib.metadata
import importlib.util
import io
import os
import statistics
import sys
import time
import warnings

warnings.filterwarnings("ignore")


def parse():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="256,512")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--slow", action="store_true", help="also run medpy and surface-distance at 512³ (minutes each)")
    ap.add_argument("--phantom", type=int, default=256, help="phantom size for the interpolation rows")
    ap.add_argument("--skip", type=int, default=4, help="slices skipped between traced ones for the interpolation rows (4: every 5th)")
    ap.add_argument("--only", default="", help="comma-separated sections: distance,overlap,interpolation")
    ap.add_argument("--cache", default="", help="folder to keep the generated blob pairs in (.npy), to skip generating them again")
    return ap.parse_args()


args = parse()
# rayon reads this when its pool starts (the first interslice call).
os.environ.setdefault("RAYON_NUM_THREADS", str(args.threads))

import numpy as np  # noqa: E402

import interslice  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blobs import SPACING_XYZ, checked_pair  # noqa: E402

SP_ZYX = tuple(reversed(SPACING_XYZ))


def run_times(fn, reps):
    """(the times of up to `reps` runs of fn, its last result)."""
    ts, val = [], None
    for _ in range(reps):
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            t0 = time.perf_counter()
            val = fn()
            ts.append(time.perf_counter() - t0)
        if ts[0] > 60:  # one run of a slow library is enough
            break
    return ts, val


def timed(fn, reps):
    """(median seconds of up to `reps` runs of fn, its last result)."""
    ts, val = run_times(fn, reps)
    return statistics.median(ts), val


def optional(name):
    try:
        return __import__(name)
    except Exception:  # noqa: BLE001 - any import failure means "not installed"
        return None


sitk = optional("SimpleITK")
torch = optional("torch")
monai_metrics = None
if torch is not None:
    torch.set_num_threads(args.threads)
    try:
        import monai.metrics as monai_metrics
    except Exception:  # noqa: BLE001
        monai_metrics = None
if sitk is not None:
    sitk.ProcessObject.SetGlobalDefaultNumberOfThreads(args.threads)


class Table:
    def __init__(self, title):
        self.title, self.rows = title, []

    def add(self, name, secs, value, base=None):
        self.rows.append((name, secs, value, base))
        ratio = "" if base is None else f"{secs / base:8.1f}x"
        print(f"  {name:58s} {secs:9.4f} s {ratio:>9s}   {value}", flush=True)


def fmt(d):
    return ", ".join(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}" for k, v in d.items())


# --------------------------------------------------------------------- distances
def sitk_contour_maurer(G, P):
    def directed(A, B):
        dm = sitk.Abs(sitk.SignedMaurerDistanceMap(B, squaredDistance=False, useImageSpacing=True))
        c = sitk.LabelContour(A, fullyConnected=False)
        return sitk.GetArrayViewFromImage(dm)[sitk.GetArrayViewFromImage(c) > 0].astype(np.float64)

    a, b = directed(P, G), directed(G, P)
    allv = np.concatenate([a, b])
    return {"hd95_pooled": float(np.percentile(allv, 95)), "mean_pooled": float(allv.mean())}


def medpy_dist(g, p):
    from medpy.metric import binary as mb

    return {"hd95": mb.hd95(p, g, voxelspacing=SP_ZYX), "assd": mb.assd(p, g, voxelspacing=SP_ZYX)}


def monai_dist(yg, yp):
    hd95 = monai_metrics.compute_hausdorff_distance(yp, yg, include_background=True, percentile=95, spacing=list(SP_ZYX))
    asd = monai_metrics.compute_average_surface_distance(
        yp, yg, include_background=True, symmetric=True, spacing=list(SP_ZYX)
    )
    return {"hd95": hd95[0, 0].item(), "assd": asd[0, 0].item()}


def surface_distance_dist(gb, pb):
    import surface_distance as sd

    d = sd.compute_surface_distances(gb, pb, list(SP_ZYX))
    a = sd.compute_average_surface_distance(d)
    return {"hd95": sd.compute_robust_hausdorff(d, 95), "asd": (a[0] + a[1]) / 2}


def interslice_dist(g, p):
    m = interslice.evaluate(g.T, p.T, SPACING_XYZ, label=1)
    return {"hd95": m["hd95"], "hd95_pooled": m["hd95_pooled"], "assd": m["assd"], "dice": m["dice"]}


# --------------------------------------------------------------------- overlap
def sitk_overlap(G, P):
    f = sitk.LabelOverlapMeasuresImageFilter()
    f.Execute(P, G)
    return {"dice": f.GetDiceCoefficient(), "jaccard": f.GetJaccardCoefficient()}


def medpy_overlap(gb, pb):
    from medpy.metric import binary as mb

    return {"dice": mb.dc(pb, gb), "jaccard": mb.jc(pb, gb), "sens": mb.sensitivity(pb, gb), "spec": mb.specificity(pb, gb)}


def monai_overlap(yg, yp):
    d = monai_metrics.compute_dice(yp, yg, include_background=True)[0, 0].item()
    cm = monai_metrics.get_confusion_matrix(yp, yg, include_background=True)
    return {"dice": d, "sens": monai_metrics.compute_confusion_matrix_metric("sensitivity", cm)[0, 0].item()}


def interslice_overlap(g, p):
    m = interslice.overlap(g.T, p.T, label=1, spacing=SPACING_XYZ)
    return {"dice": m["dice"], "jaccard": m["jaccard"], "sens": m["sensitivity"], "spec": m["specificity"]}


def cached_pair(n):
    if not args.cache:
        return checked_pair(n)
    os.makedirs(args.cache, exist_ok=True)
    paths = [os.path.join(args.cache, f"blob{n}_{r}.npy") for r in ("gt", "pred")]
    if all(os.path.exists(q) for q in paths):
        return tuple(np.load(q) for q in paths)
    pair = checked_pair(n)
    for q, a in zip(paths, pair):
        np.save(q, a)
    return pair


def metrics_section(n, want):
    print(f"\n== blob pair {n}³ (spacing {SPACING_XYZ} µm, {args.threads} threads)", flush=True)
    t0 = time.perf_counter()
    g, p = cached_pair(n)
    print(f"  (generated in {time.perf_counter() - t0:.1f} s; I/O and conversions outside the timings)")
    gb, pb = g.astype(bool), p.astype(bool)
    G = P = yg = yp = None
    if sitk is not None:
        G, P = sitk.GetImageFromArray(g), sitk.GetImageFromArray(p)
        G.SetSpacing(SPACING_XYZ)
        P.SetSpacing(SPACING_XYZ)
    if monai_metrics is not None:
        yg = torch.from_numpy(g.astype(np.float32))[None, None]
        yp = torch.from_numpy(p.astype(np.float32))[None, None]
    slow_ok = n <= 256 or args.slow
    if "distance" in want:
        t = Table("distance")
        print("  -- HD95 + mean surface distance")
        base, val = timed(lambda: interslice_dist(g, p), args.reps)
        t.add("interslice.evaluate (every metric)", base, fmt(val))
        if sitk is not None:
            s, v = timed(lambda: sitk_contour_maurer(G, P), args.reps)
            t.add("SimpleITK LabelContour + SignedMaurerDistanceMap x2", s, fmt(v), base)
        if monai_metrics is not None:
            s, v = timed(lambda: monai_dist(yg, yp), args.reps)
            t.add("MONAI compute_hausdorff_distance + average_surface", s, fmt(v), base)
        if optional("medpy") is not None and slow_ok:
            s, v = timed(lambda: medpy_dist(gb, pb), args.reps)
            t.add("medpy hd95 + assd", s, fmt(v), base)
        if optional("surface_distance") is not None and slow_ok:
            s, v = timed(lambda: surface_distance_dist(gb, pb), args.reps)
            t.add("surface-distance surface distances + hd95 + asd", s, fmt(v), base)
    if "overlap" in want:
        t = Table("overlap")
        print("  -- overlap only (Dice, Jaccard, sensitivity, specificity)")
        base, val = timed(lambda: interslice_overlap(g, p), args.reps)
        t.add("interslice.overlap", base, fmt(val))
        if sitk is not None:
            s, v = timed(lambda: sitk_overlap(G, P), args.reps)
            t.add("SimpleITK LabelOverlapMeasuresImageFilter", s, fmt(v), base)
        if optional("medpy") is not None:
            s, v = timed(lambda: medpy_overlap(gb, pb), args.reps)
            t.add("medpy dc + jc + sensitivity + specificity", s, fmt(v), base)
        if monai_metrics is not None:
            s, v = timed(lambda: monai_overlap(yg, yp), args.reps)
            t.add("MONAI compute_dice + confusion matrix", s, fmt(v), base)
        s, v = timed(lambda: int(np.count_nonzero(g == p)), args.reps)
        t.add("(floor) numpy count_nonzero(g == p)", s, f"equal voxels {v}", base)


# --------------------------------------------------------------------- interpolation
def sdf_blend(sparse_zyx, drawn, sp_zyx):
    """Plain signed-distance blending between consecutive drawn z slices."""
    from scipy import ndimage as ndi

    out = sparse_zyx.astype(bool).copy()

    def sdf(m):
        if not m.any():
            return np.full(m.shape, 1e9)
        inside = ndi.distance_transform_edt(m, sampling=sp_zyx[1:])
        outside = ndi.distance_transform_edt(~m, sampling=sp_zyx[1:])
        return outside - inside

    prev = None
    for k in drawn:
        cur = sdf(sparse_zyx[k] != 0)
        if prev is not None:
            k0, d0 = prev
            for z in range(k0 + 1, k):
                t = (z - k0) / (k - k0)
                out[z] = (1 - t) * d0 + t * cur < 0
        prev = (k, cur)
    return out


#: Run in a child process by ``ItkMci``: the ``itk`` package and SimpleITK
#: each carry their own copy of ITK, and the two in one process corrupt the
#: heap when the interpreter exits. Each line on stdin asks for that many
#: timed runs, after ``WARM_UP`` untimed ones; their times come back as one
#: line.
ITK_CHILD = """
import sys, time
import numpy as np
import itk
itk.MultiThreaderBase.SetGlobalDefaultNumberOfThreads(int(sys.argv[2]))
a = np.load(sys.argv[1])
out = None
print("ready", flush=True)
for line in sys.stdin:
    ts = []
    for i in range(int(sys.argv[3]) + int(line)):
        t0 = time.perf_counter()
        f = itk.MorphologicalContourInterpolator.New(itk.image_from_array(a))
        f.SetAxis(2)
        f.Update()
        out = itk.array_from_image(f.GetOutput()) != 0
        if i >= int(sys.argv[3]):
            ts.append(time.perf_counter() - t0)
    print(" ".join(map(str, ts)), flush=True)
np.save(sys.argv[1], out)
"""


#: Untimed runs at the start of each round, on either side: the first two
#: calls after the other side's round run up to twice as slow (seen with
#: pauses of up to 3 s between rounds), which is the machine settling, not
#: the method.
WARM_UP = 2


class ItkMci:
    """ITK's morphological contour interpolation along z, timed in a child
    process (see ``ITK_CHILD``) in rounds the caller asks for, so that its
    runs can alternate with interslice's: the two are then timed under the
    same load of the machine, which drifts over seconds."""

    def __init__(self, sparse_zyx):
        import subprocess
        import tempfile

        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "sparse.npy")
        np.save(self.path, np.ascontiguousarray(sparse_zyx.astype(np.uint8)))
        self.proc = subprocess.Popen(
            [sys.executable, "-c", ITK_CHILD, self.path, str(args.threads), str(WARM_UP)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        if self.proc.stdout.readline().strip() != "ready":
            raise RuntimeError(self.proc.communicate()[1].strip().splitlines()[-1:])

    def run(self, reps):
        """Times of `reps` runs."""
        self.proc.stdin.write(f"{reps}\n")
        self.proc.stdin.flush()
        return [float(t) for t in self.proc.stdout.readline().split()]

    def result(self):
        """The last run's mask; ends the child."""
        _, err = self.proc.communicate()
        if self.proc.returncode != 0:
            raise RuntimeError(err.strip().splitlines()[-1:])
        out = np.load(self.path)
        self.dir.cleanup()
        return out


def dice(a, b):
    a, b = a != 0, b != 0
    return 2 * np.count_nonzero(a & b) / (np.count_nonzero(a) + np.count_nonzero(b))


def interpolation_section():
    n = args.phantom
    step = args.skip + 1
    print(f"\n== interpolation: phantom nucleus {n}³, traced on every {step}th z slice", flush=True)
    _, labels, meta = interslice.phantom(size=n, seed=1)
    truth = (labels >= 2).astype(np.uint8).T  # [z, y, x], nucleus with its nucleoli
    drawn = [z for z in range(0, n, step)]
    sparse = np.zeros_like(truth)
    sparse[drawn] = truth[drawn]
    sp = meta["spacing"]
    t = Table("interpolation")

    def ours(method=None):
        return interslice.interpolate(sparse.T, drawn=drawn, axis=2, spacing=sp, method=method)

    # The default and ITK MCI alternate in rounds (ITK in its child process),
    # so that their ratio is taken under the same load of the machine.
    itk = None
    if importlib.util.find_spec("itk") is not None:
        try:
            itk = ItkMci(sparse)
        except Exception as e:  # noqa: BLE001
            print(f"  ITK morphological contour interpolation failed: {e}")
    rounds = min(5, args.reps)
    ours_ts, itk_ts = [], []
    for r in range(rounds):
        n = args.reps // rounds + (r < args.reps % rounds)
        run_times(ours, WARM_UP)
        ts, out = run_times(ours, n)
        ours_ts += ts
        if itk is not None:
            itk_ts += itk.run(n)
    base = statistics.median(ours_ts)
    t.add(f"interslice.interpolate ({interslice.DEFAULT_METHOD})", base, f"Dice {dice(out.T, truth):.4f}")
    s, out = timed(lambda: ours("shape-based"), args.reps)
    t.add("interslice.interpolate (shape-based)", s, f"Dice {dice(out.T, truth):.4f}", base)
    if itk is not None:
        try:
            t.add("ITK MorphologicalContourInterpolator", statistics.median(itk_ts), f"Dice {dice(itk.result(), truth):.4f}", base)
        except Exception as e:  # noqa: BLE001
            print(f"  ITK morphological contour interpolation failed: {e}")
    if optional("scipy") is not None:
        s, out = timed(lambda: sdf_blend(sparse, drawn, tuple(reversed(sp))), args.reps)
        t.add("scipy signed-distance blending (1 core)", s, f"Dice {dice(out, truth):.4f}", base)


def main():
    want = set(args.only.split(",")) if args.only else {"distance", "overlap", "interpolation"}
    versions = {"interslice": interslice.__version__, "numpy": np.__version__}
    for mod in ("SimpleITK", "torch", "monai", "medpy", "scipy"):
        m = optional(mod)
        if m is not None:
            versions[mod] = getattr(m, "__version__", "?")
    if importlib.util.find_spec("itk") is not None:
        versions["itk"] = importlib.metadata.version("itk")
    print(f"threads {args.threads}, reps {args.reps}; " + ", ".join(f"{k} {v}" for k, v in versions.items()))
    print(f"load average at start {os.getloadavg()}")
    print("  row" + " " * 56 + "time      ratio   values (ratio = its time / interslice's)")
    if want & {"distance", "overlap"}:
        for n in (int(s) for s in args.sizes.split(",")):
            metrics_section(n, want)
    if "interpolation" in want:
        interpolation_section()
    print(f"\nload average at end {os.getloadavg()}")


if __name__ == "__main__":
    main()
