#!/usr/bin/env python3
"""Cross-checks interslice's volume formats against SimpleITK, nibabel and tifffile.

(a) Files that interslice writes (`interslice convert` from a SimpleITK file)
    are read by SimpleITK (and nibabel for NIfTI, tifffile for TIFF) with the
    same array, spacing, origin and direction.
(c) 3D Slicer segmentations (.seg.nrrd) we write read in pynrrd and SimpleITK
    with their segment names, colours and values, and read back (see part_c).
(b) Files that SimpleITK, nibabel and tifffile write are read by interslice
    with the same values: `interslice info --json` for the geometry, type and
    range, and `interslice convert` to MetaImage for the voxels.

Arrays: numpy and SimpleITK index [z, y, x]; nibabel indexes [x, y, z]. ITK
geometry is LPS; nibabel's affine is RAS (the first two rows negated).
Prints each failed check (every check with --verbose) and a closing
"N passed, M failed"; exits 1 on any mismatch.

Usage: crosscheck_formats.py --bin target/debug/interslice
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import nibabel as nib
import nrrd
import numpy as np
import SimpleITK as sitk
import tifffile

NX, NY, NZ = 7, 5, 4
SPACING = (0.35, 0.5, 1.25)
ORIGIN = (-3.5, 12.25, 7.0)
# A 30 degree rotation about z with the z axis flipped (ITK row-major).
C, S = np.sqrt(0.75), 0.5
OBLIQUE = (C, -S, 0.0, S, C, 0.0, 0.0, 0.0, -1.0)
IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

results = {"passed": 0, "failed": 0}
VERBOSE = False


def check(name, ok, detail=""):
    if ok:
        results["passed"] += 1
        if VERBOSE:
            print(f"ok    {name}")
    else:
        results["failed"] += 1
        print(f"FAIL  {name}: {detail}")


def close(a, b, tol):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= tol * np.maximum(1.0, np.abs(b))))


def volume(dtype):
    """A [z, y, x] array that uses the type's range and tells axes apart."""
    k, j, i = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    n = i + NX * (j + NY * k)
    if dtype == np.uint8:
        return ((n * 7) % 256).astype(np.uint8)
    if dtype == np.uint16:
        return ((n * 613) % 65536).astype(np.uint16)
    if dtype == np.int16:
        return ((n * 331) % 65536 - 32768).astype(np.int16)
    return (n * 0.1 - 7.25).astype(np.float32)


def sitk_image(arr, direction=IDENTITY):
    img = sitk.GetImageFromArray(arr)
    img.SetSpacing(SPACING)
    img.SetOrigin(ORIGIN)
    img.SetDirection(direction)
    return img


def run(binary, *args):
    p = subprocess.run([binary, *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"interslice {' '.join(args)} failed: {p.stderr.strip()}")
    return p.stdout


def compare_sitk(name, path, arr, direction):
    img = sitk.ReadImage(path)
    got = sitk.GetArrayFromImage(img)
    check(f"{name}: SimpleITK array", got.dtype == arr.dtype and np.array_equal(got, arr),
          f"dtype {got.dtype} vs {arr.dtype}, equal={np.array_equal(got, arr) if got.shape == arr.shape else got.shape}")
    check(f"{name}: SimpleITK spacing", close(img.GetSpacing(), SPACING, 1e-6), img.GetSpacing())
    check(f"{name}: SimpleITK origin", close(img.GetOrigin(), ORIGIN, 1e-6), img.GetOrigin())
    check(f"{name}: SimpleITK direction", close(img.GetDirection(), direction, 1e-6), img.GetDirection())


def compare_nibabel(name, path, arr, direction, unit="mm"):
    img = nib.load(path)
    got = np.asanyarray(img.dataobj).transpose(2, 1, 0)  # [x,y,z] -> [z,y,x]
    check(f"{name}: nibabel array", got.dtype == arr.dtype and np.array_equal(got, arr), got.dtype)
    check(f"{name}: nibabel spacing", close(img.header.get_zooms()[:3], SPACING, 1e-6), img.header.get_zooms())
    check(f"{name}: nibabel unit", img.header.get_xyzt_units()[0] == unit, img.header.get_xyzt_units())
    aff = img.affine
    lps = np.diag([-1.0, -1.0, 1.0])
    origin = lps @ aff[:3, 3]
    check(f"{name}: nibabel origin", close(origin, ORIGIN, 1e-6), origin)
    d = lps @ aff[:3, :3] / np.asarray(SPACING)
    check(f"{name}: nibabel direction", close(d.ravel(), direction, 1e-6), d.ravel())


def compare_tifffile(name, path, arr):
    with tifffile.TiffFile(path) as t:
        got = t.asarray()
        meta = t.imagej_metadata or {}
        xres = t.pages[0].tags["XResolution"].value
        yres = t.pages[0].tags["YResolution"].value
    check(f"{name}: tifffile array", got.dtype == arr.dtype and np.array_equal(got, arr), got.dtype)
    sx, sy = xres[1] / xres[0], yres[1] / yres[0]
    sz = float(meta.get("spacing", 0))
    check(f"{name}: tifffile ImageJ spacing", close((sx, sy, sz), SPACING, 1e-9), (sx, sy, sz))
    check(f"{name}: tifffile ImageJ unit", meta.get("unit") == "micron", meta.get("unit"))


def part_a(binary, tmp):
    """interslice writes, the libraries read."""
    for dtype in (np.uint8, np.uint16, np.int16, np.float32):
        for direction, dname in ((IDENTITY, "axial"), (OBLIQUE, "oblique")):
            arr = volume(dtype)
            src = os.path.join(tmp, f"a_src_{np.dtype(dtype).name}_{dname}.mha")
            sitk.WriteImage(sitk_image(arr, direction), src)
            for ext in (".nii.gz", ".nii", ".nrrd", ".mha", ".mhd"):
                out = os.path.join(tmp, f"a_{np.dtype(dtype).name}_{dname}{ext}")
                run(binary, "convert", src, out)
                name = f"(a) {np.dtype(dtype).name} {dname} {ext}"
                compare_sitk(name, out, arr, direction)
                if ext.startswith(".nii"):
                    compare_nibabel(name, out, arr, direction)
    # nibabel reads our NIfTI files: the unit (micrometres) comes from an
    # ImageJ TIFF, origin and direction from an oblique MetaImage. tifffile
    # reads our ImageJ TIFF.
    for dtype in (np.uint8, np.uint16):
        arr = volume(dtype)
        tname = np.dtype(dtype).name
        tif = os.path.join(tmp, f"a_src_{tname}.tif")
        tifffile.imwrite(tif, arr, imagej=True, resolution=(1 / SPACING[0], 1 / SPACING[1]),
                         metadata={"spacing": SPACING[2], "unit": "micron", "axes": "ZYX"})
        mha = os.path.join(tmp, f"a_src_{tname}_oblique.mha")
        sitk.WriteImage(sitk_image(arr, OBLIQUE), mha)
        for ext in (".nii.gz", ".nii"):
            out = os.path.join(tmp, f"a_nib_{tname}{ext}")
            run(binary, "convert", tif, out)
            img = nib.load(out)
            got = np.asanyarray(img.dataobj).transpose(2, 1, 0)
            name = f"(a) {tname} {ext} from an ImageJ TIFF"
            check(f"{name}: nibabel array", got.dtype == arr.dtype and np.array_equal(got, arr), got.dtype)
            check(f"{name}: nibabel spacing", close(img.header.get_zooms()[:3], SPACING, 1e-6),
                  img.header.get_zooms())
            check(f"{name}: nibabel unit", img.header.get_xyzt_units()[0] == "micron",
                  img.header.get_xyzt_units())
            out = os.path.join(tmp, f"a_nib_{tname}_oblique{ext}")
            run(binary, "convert", mha, out)
            img = nib.load(out)
            lps = np.diag([-1.0, -1.0, 1.0])
            origin = lps @ img.affine[:3, 3]
            d = lps @ img.affine[:3, :3] / np.asarray(SPACING)
            name = f"(a) {tname} oblique {ext}"
            check(f"{name}: nibabel origin", close(origin, ORIGIN, 1e-6), origin)
            check(f"{name}: nibabel direction", close(d.ravel(), OBLIQUE, 1e-6), d.ravel())
        out = os.path.join(tmp, f"a_{tname}.tif")
        run(binary, "convert", tif, out)
        compare_tifffile(f"(a) {tname} .tif", out, arr)


def compare_info(name, path, arr, direction, unit="mm"):
    info = json.loads(run(binary_path, "info", "--json", path))
    check(f"{name}: info dims", info["dims"] == [NX, NY, NZ], info["dims"])
    check(f"{name}: info spacing", close(info["spacing"], SPACING, 1e-6), info["spacing"])
    check(f"{name}: info origin", close(info["origin"], ORIGIN, 1e-6), info["origin"])
    d = np.asarray(info["direction"]).ravel()
    check(f"{name}: info direction", close(d, direction, 1e-6), d)
    want_type = {"uint8": "u8", "uint16": "u16", "int16": "i16", "float32": "f32"}[arr.dtype.name]
    check(f"{name}: info type", info["dtype"] == want_type, info["dtype"])
    check(f"{name}: info range", close([info["min"], info["max"]], [arr.min(), arr.max()], 1e-7),
          (info["min"], info["max"]))
    check(f"{name}: info unit", info["unit"] == unit, info["unit"])


def compare_voxels(name, path, arr, tmp):
    back = os.path.join(tmp, "back_" + os.path.basename(path).replace(".", "_") + ".mha")
    run(binary_path, "convert", path, back)
    got = sitk.GetArrayFromImage(sitk.ReadImage(back))
    check(f"{name}: voxels read by interslice", got.dtype == arr.dtype and np.array_equal(got, arr),
          got.dtype)


def part_b(tmp):
    """The libraries write, interslice reads."""
    for dtype in (np.uint8, np.uint16, np.int16, np.float32):
        for direction, dname in ((IDENTITY, "axial"), (OBLIQUE, "oblique")):
            arr = volume(dtype)
            for ext, compress in ((".nii.gz", True), (".nii", False), (".nrrd", True),
                                  (".nrrd", False), (".mha", True), (".mha", False), (".mhd", False)):
                tag = "gz" if compress else "raw"
                path = os.path.join(tmp, f"b_{np.dtype(dtype).name}_{dname}_{tag}{ext}")
                sitk.WriteImage(sitk_image(arr, direction), path, useCompression=compress)
                name = f"(b) SimpleITK {np.dtype(dtype).name} {dname} {ext} {tag}"
                compare_info(name, path, arr, direction)
                compare_voxels(name, path, arr, tmp)
    # nibabel NIfTI in micrometres with an oblique RAS affine.
    for dtype in (np.uint8, np.uint16, np.int16, np.float32):
        arr = volume(dtype)
        lps = np.diag([-1.0, -1.0, 1.0])
        aff = np.eye(4)
        aff[:3, :3] = lps @ np.asarray(OBLIQUE).reshape(3, 3) * np.asarray(SPACING)
        aff[:3, 3] = lps @ np.asarray(ORIGIN)
        img = nib.Nifti1Image(arr.transpose(2, 1, 0), aff)
        img.header.set_xyzt_units(xyz="micron")
        img.set_qform(aff, code=1)
        img.set_sform(aff, code=1)
        path = os.path.join(tmp, f"b_nib_{np.dtype(dtype).name}.nii.gz")
        nib.save(img, path)
        name = f"(b) nibabel {np.dtype(dtype).name} .nii.gz"
        compare_info(name, path, arr, OBLIQUE, unit="µm")
        compare_voxels(name, path, arr, tmp)
    # tifffile ImageJ stacks (no origin: 0).
    for dtype in (np.uint8, np.uint16, np.float32):
        arr = volume(dtype)
        path = os.path.join(tmp, f"b_tifffile_{np.dtype(dtype).name}.tif")
        tifffile.imwrite(path, arr, imagej=True, resolution=(1 / SPACING[0], 1 / SPACING[1]),
                         metadata={"spacing": SPACING[2], "unit": "micron", "axes": "ZYX"})
        info = json.loads(run(binary_path, "info", "--json", path))
        name = f"(b) tifffile {np.dtype(dtype).name} .tif"
        check(f"{name}: info dims", info["dims"] == [NX, NY, NZ], info["dims"])
        check(f"{name}: info spacing", close(info["spacing"], SPACING, 1e-9), info["spacing"])
        check(f"{name}: info unit", info["unit"] == "µm", info["unit"])
        compare_voxels(name, path, arr, tmp)
    # A folder of 2D TIFF slices named slice_1 ... slice_12 (natural order).
    folder = os.path.join(tmp, "b_slices")
    os.makedirs(folder)
    planes = []
    for n in range(12):
        plane = ((np.arange(NX * NY).reshape(NY, NX) * 3 + n * 17) % 65536).astype(np.uint16)
        planes.append(plane)
        tifffile.imwrite(os.path.join(folder, f"slice_{n + 1}.tif"), plane)
    back = os.path.join(tmp, "b_slices.mha")
    run(binary_path, "convert", folder, back)
    got = sitk.GetArrayFromImage(sitk.ReadImage(back))
    check("(b) tifffile slice folder in natural order", np.array_equal(got, np.stack(planes)), got.shape)


binary_path = ""


def part_c(binary, tmp):
    """(c) Segment tables: a .seg.nrrd we write is read by pynrrd and SimpleITK
    with 3D Slicer's segment names, colours and label values; an ITK-SNAP label
    description file is written beside other label volumes; both read back."""
    labels = np.zeros((NZ, NY, NX), dtype=np.uint8)
    labels[1:3, 1:4, 2:5] = 1
    labels[3, 2, 3] = 2
    labels[0, 0, 0] = 5
    src = os.path.join(tmp, "labels_src.nii.gz")
    sitk.WriteImage(sitk_image(labels), src)
    seg = os.path.join(tmp, "out.seg.nrrd")
    run(binary, "convert", src, seg, "--components", "Tumour,Oedema")
    data, header = nrrd.read(seg)
    check("(c) pynrrd seg.nrrd voxels", np.array_equal(data, labels.transpose(2, 1, 0)), data.shape)
    segs = {}
    n = 0
    while f"Segment{n}_LabelValue" in header:
        segs[int(header[f"Segment{n}_LabelValue"])] = (
            header[f"Segment{n}_Name"],
            [float(c) for c in header[f"Segment{n}_Color"].split()],
            header[f"Segment{n}_Layer"],
        )
        n += 1
    check("(c) pynrrd segment names", {k: v[0] for k, v in segs.items()} == {1: "Tumour", 2: "Oedema", 5: "Label 5"}, segs)
    check("(c) pynrrd segment colours", close(segs[1][1], [0xE6 / 255, 0x19 / 255, 0x4B / 255], 1e-5), segs.get(1))
    check("(c) pynrrd segment layers", all(v[2] == "0" for v in segs.values()), segs)
    check("(c) Slicer representation", header.get("Segmentation_MasterRepresentation") == "Binary labelmap", header)
    img = sitk.ReadImage(seg)
    check("(c) SimpleITK seg.nrrd voxels", np.array_equal(sitk.GetArrayFromImage(img), labels), img.GetSize())
    check("(c) SimpleITK seg.nrrd spacing", close(img.GetSpacing(), SPACING, 1e-6), img.GetSpacing())
    check("(c) SimpleITK segment name", img.GetMetaData("Segment1_Name") == "Oedema", img.GetMetaDataKeys())
    # Back: our reader keeps the values and the names (--label by name).
    back = os.path.join(tmp, "back.nii.gz")
    run(binary, "convert", seg, back)
    txt = os.path.join(tmp, "back.label.txt")
    check("(c) ITK-SNAP label description beside the volume", os.path.isfile(txt), os.listdir(tmp))
    if os.path.isfile(txt):
        lines = [ln for ln in open(txt) if not ln.startswith("#")]
        check("(c) ITK-SNAP description rows", any('"Tumour"' in ln and ln.split()[:4] == ["1", "230", "25", "75"] for ln in lines), lines)
    out = json.loads(run(binary, "evaluate", seg, back, "--label", "oedema", "--json"))
    check("(c) --label by name through the segment table", out["label"] == 2 and out["dice"] == 1.0, out)


def main():
    global binary_path
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", required=True, help="path of the interslice binary")
    ap.add_argument("--verbose", action="store_true", help="print every check, not only failures")
    args = ap.parse_args()
    global VERBOSE
    VERBOSE = args.verbose
    binary_path = os.path.abspath(args.bin)
    with tempfile.TemporaryDirectory(prefix="interslice-crosscheck-") as tmp:
        part_a(binary_path, tmp)
        part_b(tmp)
        part_c(binary_path, tmp)
    print(f"{results['passed']} passed, {results['failed']} failed")
    return 1 if results["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
