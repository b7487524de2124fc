// Reads a NIfTI (.nii / .nii.gz) label or intensity volume into a flat
// x-fastest typed array with its dims, using nifti-reader-js.
import * as nifti from "nifti-reader-js";

/** @returns {{dims:number[], spacing:number[], data: ArrayLike<number>}} */
export function readNifti(buf) {
  let ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  if (nifti.isCompressed(ab)) ab = nifti.decompress(ab);
  if (!nifti.isNIFTI(ab)) throw new Error("not a NIfTI file");
  const hdr = nifti.readHeader(ab);
  const img = nifti.readImage(hdr, ab);
  const [nx, ny, nz] = [hdr.dims[1], hdr.dims[2], Math.max(1, hdr.dims[3])];
  const n = nx * ny * nz;
  const le = hdr.littleEndian;
  const dv = new DataView(img);
  const data = new Float64Array(n);
  const code = hdr.datatypeCode;
  const get = {
    2: (p) => dv.getUint8(p),
    256: (p) => dv.getInt8(p),
    4: (p) => dv.getInt16(2 * p, le),
    512: (p) => dv.getUint16(2 * p, le),
    8: (p) => dv.getInt32(4 * p, le),
    768: (p) => dv.getUint32(4 * p, le),
    16: (p) => dv.getFloat32(4 * p, le),
    64: (p) => dv.getFloat64(8 * p, le),
  }[code];
  if (!get) throw new Error(`NIfTI datatype ${code} not supported here`);
  for (let p = 0; p < n; p++) data[p] = get(p);
  return { dims: [nx, ny, nz], spacing: [hdr.pixDims[1], hdr.pixDims[2], hdr.pixDims[3]], data };
}
