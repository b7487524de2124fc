//! Volume and mesh file formats: NIfTI, NRRD, MetaImage, TIFF, slice folders, DICOM.
#![deny(missing_docs)]
