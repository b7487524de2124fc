"""Writes the golden files of crates/io/tests/integration/golden.rs with established libraries.

Run once (python3 make_golden.py, with SimpleITK, nibabel, tifffile, numpy and
pynrrd installed) and commit the output; the tests assert exact values.
Every volume has dims (nx, ny, nz) = (5, 4, 3) and voxel (i, j, k) holds
base + i + 10*j + 100*k (u8: i + 5*j + 20*k).
"""
import os

import nibabel as nib
import nrrd
import numpy as np
import SimpleITK as sitk
import tifffile

HERE = os.path.dirname(os.path.abspath(__file__))
NX, NY, NZ = 5, 4, 3
k, j, i = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")  # [z, y, x]
ZYX_U16 = (1000 + i + 10 * j + 100 * k).astype(np.uint16)
ZYX_U8 = (i + 5 * j + 20 * k).astype(np.uint8)
ZYX_I16 = (-500 + i + 10 * j + 100 * k).astype(np.int16)
ZYX_F32 = (0.25 * (i + 10 * j + 100 * k) - 3.0).astype(np.float32)


def out(name):
    return os.path.join(HERE, name)


def sitk_image(arr, spacing, origin, direction=None):
    img = sitk.GetImageFromArray(arr)  # numpy [z, y, x] -> image (x, y, z)
    img.SetSpacing(spacing)
    img.SetOrigin(origin)
    if direction is not None:
        img.SetDirection(direction)
    return img


# NIfTI by nibabel: array indexed [x, y, z]; RAS affine; micrometres.
aff = np.diag([0.35, 0.5, 1.25, 1.0])
aff[:3, 3] = [10.0, -20.0, 2.5]
img = nib.Nifti1Image(ZYX_U16.transpose(2, 1, 0), aff)
img.header.set_xyzt_units(xyz="micron")
img.set_qform(aff, code=1)
img.set_sform(aff, code=1)
nib.save(img, out("nibabel_u16.nii.gz"))

# NRRD by SimpleITK (gzip), u8, with a flipped direction.
sitk.WriteImage(
    sitk_image(ZYX_U8, (0.5, 0.75, 2.0), (1.5, -2.5, 3.0), (-1, 0, 0, 0, 1, 0, 0, 0, 1)),
    out("sitk_u8.nrrd"),
    useCompression=True,
)
# MetaImage by SimpleITK: .mha zlib i16, .mhd + .raw f32.
sitk.WriteImage(sitk_image(ZYX_I16, (0.35, 0.35, 0.7), (-1.0, 2.0, -3.0)), out("sitk_i16.mha"), useCompression=True)
sitk.WriteImage(sitk_image(ZYX_F32, (1.0, 2.0, 3.0), (0.0, 0.0, 0.0)), out("sitk_f32.mhd"))

# Multi-page ImageJ TIFF by tifffile, u16, 0.35 x 0.35 x 1.05 micron.
tifffile.imwrite(
    out("tifffile_u16.tif"),
    ZYX_U16,
    imagej=True,
    resolution=(1 / 0.35, 1 / 0.35),
    metadata={"spacing": 1.05, "unit": "micron", "axes": "ZYX"},
)

# A folder of 2D TIFF slices by tifffile, named so that natural order differs
# from plain string order (slice_2 before slice_10), u8, 12 slices.
folder = out("tifffile_slices")
os.makedirs(folder, exist_ok=True)
for n in range(12):
    plane = (np.arange(NX * NY, dtype=np.uint8).reshape(NY, NX) + 10 * n).astype(np.uint8)
    tifffile.imwrite(os.path.join(folder, f"slice_{n + 1}.tif"), plane)

# A 3D Slicer-style segmentation with two layers (overlapping segments),
# written by pynrrd. Layer 0: segment "cell" (value 1) and "nucleus" (value 2);
# layer 1: segment "nucleolus" (value 1) inside the nucleus.
layers = np.zeros((2, NX, NY, NZ), dtype=np.uint8)  # pynrrd: Fortran order, [layer, x, y, z]
layers[0, 1:4, 1:3, :] = 1
layers[0, 2, 1:3, 1:2] = 2
layers[1, 2, 2, 1] = 1
header = {
    "type": "unsigned char",
    "dimension": 4,
    "space": "right-anterior-superior",
    "sizes": [2, NX, NY, NZ],
    "space directions": [[np.nan] * 3, [-0.5, 0, 0], [0, -0.5, 0], [0, 0, 1.0]],
    "kinds": ["list", "domain", "domain", "domain"],
    "encoding": "gzip",
    "space origin": [4.0, 3.0, -1.0],
    "Segment0_ID": "cell",
    "Segment0_Name": "cell",
    "Segment0_LabelValue": "1",
    "Segment0_Layer": "0",
    "Segment1_ID": "nucleus",
    "Segment1_Name": "nucleus",
    "Segment1_LabelValue": "2",
    "Segment1_Layer": "0",
    "Segment2_ID": "nucleolus",
    "Segment2_Name": "nucleolus",
    "Segment2_LabelValue": "1",
    "Segment2_Layer": "1",
    "Segmentation_MasterRepresentation": "Binary labelmap",
}
nrrd.write(out("layers.seg.nrrd"), layers, header, index_order="F")
print("written to", HERE)
