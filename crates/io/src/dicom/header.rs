//! What one DICOM file says about its image planes, read from the header
//! alone (parsing stops before the pixel data): series, size, pixel format,
//! and the position, orientation, spacing and rescale of every frame, for
//! classic single-frame files as well as legacy and enhanced multi-frame files.
use crate::IoError;
use dicom_core::Tag;
use dicom_core::header::HasLength;
use dicom_dictionary_std::tags;
use dicom_object::file::ReadPreamble;
use dicom_object::{InMemDicomObject, OpenFileOptions};
use dicom_transfer_syntax_registry::{TransferSyntaxIndex, TransferSyntaxRegistry};
use std::path::{Path, PathBuf};

/// Most frames we accept in one file (a bound before anything is sized by it).
pub(crate) const MAX_FRAMES: usize = 1 << 16;

/// How stored pixel values are laid out (PS3.3 C.7.6.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PixelFormat {
    /// Bits per sample in the data: 8 or 16.
    pub bits_allocated: u16,
    /// Bits of each sample that hold the value.
    pub bits_stored: u16,
    /// The most significant bit of the value within the sample.
    pub high_bit: u16,
    /// Two's complement values (PixelRepresentation 1).
    pub signed: bool,
}

impl PixelFormat {
    /// Bytes per sample.
    pub fn bytes(self) -> usize {
        usize::from(self.bits_allocated / 8)
    }

    fn describe(self) -> String {
        format!(
            "{} {}-bit in {} bits",
            if self.signed { "signed" } else { "unsigned" },
            self.bits_stored,
            self.bits_allocated
        )
    }
}

impl std::fmt::Display for PixelFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe())
    }
}

/// One frame of a file: where it is and how its values are rescaled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    /// ImagePositionPatient: the LPS position (mm) of the first pixel's centre.
    pub position: Option<[f64; 3]>,
    /// ImageOrientationPatient: row direction then column direction.
    pub orientation: Option<[f64; 6]>,
    /// PixelSpacing as (x, y): the column spacing, then the row spacing.
    pub spacing: Option<[f64; 2]>,
    /// RescaleSlope.
    pub slope: f64,
    /// RescaleIntercept.
    pub intercept: f64,
}

/// The header of one DICOM image file.
#[derive(Debug, Clone)]
pub(crate) struct FileHeader {
    /// The file.
    pub path: PathBuf,
    /// SeriesInstanceUID (empty when the file has none).
    pub series_uid: String,
    /// SeriesDescription.
    pub description: String,
    /// SeriesNumber.
    pub series_number: Option<i64>,
    /// Modality ("CT", "MR", ...).
    pub modality: String,
    /// TransferSyntaxUID of the file meta group.
    pub transfer_syntax: String,
    /// Rows (image height).
    pub rows: usize,
    /// Columns (image width).
    pub cols: usize,
    /// Stored value layout.
    pub pixel: PixelFormat,
    /// Every frame, in file order (one for a classic single-frame file).
    pub frames: Vec<Frame>,
    /// SpacingBetweenSlices: used only to place the frames of a legacy
    /// multi-frame file that has no per-frame positions, and as the z
    /// spacing of a single slice.
    pub spacing_between_slices: Option<f64>,
    /// SliceThickness: the z spacing of a single slice without SpacingBetweenSlices.
    pub slice_thickness: Option<f64>,
}

/// True when the file starts with the 128-byte preamble and `DICM`.
pub(crate) fn has_dicm_magic(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 132];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head[128..] == b"DICM"
}

/// Largest DICOM file we read into memory.
const MAX_FILE_BYTES: u64 = 1 << 34;

/// The bytes of a DICOM file up to the end of its pixel data, after checking
/// that no element (in the meta group, the data set, its sequences and pixel
/// fragments) claims more bytes than the file has left. The parser reserves
/// an element's declared length before reading it, so without this check a
/// few corrupt bytes could make it allocate up to 4 GiB per element. What
/// follows the pixel data (padding, trailing bytes some scanners leave) is
/// cut off: the parser would choke on it.
pub(crate) fn load(path: &Path) -> Result<Vec<u8>, IoError> {
    let len = std::fs::metadata(path)
        .map_err(|e| IoError::read(path, e))?
        .len();
    if len > MAX_FILE_BYTES {
        return Err(IoError::unsupported(
            path,
            format!("DICOM file of {len} bytes is larger than {MAX_FILE_BYTES}"),
        ));
    }
    let mut bytes = std::fs::read(path).map_err(|e| IoError::read(path, e))?;
    if bytes.len() < 132 || &bytes[128..132] != b"DICM" {
        return Err(IoError::invalid(
            path,
            "not a DICOM file (no DICM preamble)",
        ));
    }
    let data_end = check_lengths(&bytes)
        .map_err(|e| IoError::invalid(path, format!("bad DICOM file: {e}")))?;
    bytes.truncate(data_end);
    Ok(bytes)
}

/// Parse loaded bytes (see [`load`]), up to the pixel data or all of it.
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    pixel_data: bool,
) -> Result<dicom_object::DefaultDicomObject, IoError> {
    let options = OpenFileOptions::new().read_preamble(ReadPreamble::Never);
    let options = if pixel_data {
        options
    } else {
        options.read_until(tags::PIXEL_DATA)
    };
    options
        .from_reader(&bytes[128..])
        .map_err(|e| IoError::invalid(path, format!("bad DICOM file: {e}")))
}

/// Walk every element header (values skipped, nothing allocated) and err
/// when a defined length runs past the end of the data; returns where the
/// last PixelData element ends (the end of the bytes when there is none).
fn check_lengths(bytes: &[u8]) -> Result<usize, String> {
    use dicom_core::VR;
    use dicom_encoding::decode::Decode;
    use dicom_encoding::decode::explicit_le::ExplicitVRLittleEndianDecoder;
    use std::io::Read;

    let end = bytes.len();
    let mut pos = 132;
    // The meta group (0002,xxxx) is always explicit VR little endian.
    let meta = ExplicitVRLittleEndianDecoder::default();
    let mut ts_uid = String::new();
    while pos + 2 <= end && bytes[pos..pos + 2] == [2, 0] {
        let mut cur = &bytes[pos..];
        let (h, _) = meta
            .decode_header(&mut cur)
            .map_err(|e| format!("file meta group: {e}"))?;
        pos = end - cur.len();
        let n = h
            .length()
            .get()
            .ok_or("file meta element of undefined length")? as usize;
        if n > end - pos {
            return Err(format!(
                "element {} claims {n} bytes but only {} remain",
                h.tag,
                end - pos
            ));
        }
        if h.tag == tags::TRANSFER_SYNTAX_UID {
            ts_uid = String::from_utf8_lossy(&bytes[pos..pos + n])
                .trim_end_matches(['\0', ' '])
                .to_string();
        }
        pos += n;
    }
    let Some(ts) = TransferSyntaxRegistry.get(&ts_uid) else {
        // Reported as an unknown transfer syntax by the parser.
        return Ok(end);
    };
    // A deflated data set cannot be walked in its stored form; its size is
    // bounded by the inflated stream, which the parser reads as it goes.
    if !(ts.is_codec_free() || ts.is_encapsulated_pixel_data()) {
        return Ok(end);
    }
    let Some(decoder) = ts.decoder() else {
        return Ok(end);
    };
    let mut in_fragments = false;
    let mut data_end = None;
    while pos < end {
        let mut cur = &bytes[pos..];
        // A header that does not decode is the parser's to report (or to
        // ignore, as trailing bytes after the data set often are).
        let Ok((h, _)) = decoder.decode_header(&mut cur as &mut dyn Read) else {
            return Ok(data_end.unwrap_or(end));
        };
        pos = end - cur.len();
        let Some(n) = h.length().get() else {
            // A sequence, an item or encapsulated pixel data: its content
            // follows as headers.
            in_fragments |= h.tag == tags::PIXEL_DATA;
            continue;
        };
        let is_item = h.tag == Tag(0xFFFE, 0xE000);
        if h.tag == Tag(0xFFFE, 0xE0DD) && in_fragments {
            in_fragments = false;
            data_end = Some(pos);
        }
        if (is_item && !in_fragments) || (!is_item && h.vr == VR::SQ) {
            continue;
        }
        let n = n as usize;
        if n > end - pos {
            return Err(format!(
                "element {} claims {n} bytes but only {} remain (truncated or corrupt)",
                h.tag,
                end - pos
            ));
        }
        pos += n;
        if h.tag == tags::PIXEL_DATA {
            data_end = Some(pos);
        }
    }
    Ok(data_end.unwrap_or(end))
}

/// Read the header of a DICOM file. `Ok(None)` for a DICOM object that is
/// not an image (a DICOMDIR, a structured report, a presentation state...).
pub(crate) fn read_header(path: &Path) -> Result<Option<FileHeader>, IoError> {
    let bytes = load(path)?;
    let obj = parse(path, &bytes, false)?;
    let transfer_syntax = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches(['\0', ' '])
        .to_string();
    let bad = |msg: String| IoError::invalid(path, msg);
    let (Some(rows), Some(cols)) = (
        int(&obj, tags::ROWS).map_err(bad)?,
        int(&obj, tags::COLUMNS).map_err(bad)?,
    ) else {
        return Ok(None);
    };
    if !(1..=65535).contains(&rows) || !(1..=65535).contains(&cols) {
        return Err(bad(format!("image size {cols} x {rows} is out of range")));
    }
    let samples = int(&obj, tags::SAMPLES_PER_PIXEL)
        .map_err(bad)?
        .unwrap_or(1);
    let photometric = text(&obj, tags::PHOTOMETRIC_INTERPRETATION).map_err(bad)?;
    if samples != 1 || !matches!(photometric.as_str(), "MONOCHROME1" | "MONOCHROME2" | "") {
        return Err(IoError::unsupported(
            path,
            format!(
                "colour DICOM images ({photometric}, {samples} samples per pixel) are not supported (grey images only)"
            ),
        ));
    }
    let pixel = pixel_format(&obj).map_err(bad)?;
    let n_frames = match int(&obj, tags::NUMBER_OF_FRAMES).map_err(bad)? {
        None => 1,
        Some(n) if (1..=MAX_FRAMES as i64).contains(&n) => n as usize,
        Some(n) => {
            return Err(bad(format!(
                "NumberOfFrames {n} is out of range (1..={MAX_FRAMES})"
            )));
        }
    };
    let mut frames = (0..n_frames)
        .map(|k| frame(&obj, k, n_frames))
        .collect::<Result<Vec<_>, _>>()
        .map_err(bad)?;
    let spacing_between_slices = float(&obj, tags::SPACING_BETWEEN_SLICES).map_err(bad)?;
    if n_frames > 1 && !has_per_frame_positions(&obj) {
        place_legacy_frames(&mut frames, spacing_between_slices);
    }
    Ok(Some(FileHeader {
        path: path.to_path_buf(),
        series_uid: text(&obj, tags::SERIES_INSTANCE_UID).map_err(bad)?,
        description: text(&obj, tags::SERIES_DESCRIPTION).map_err(bad)?,
        series_number: int(&obj, tags::SERIES_NUMBER).unwrap_or(None),
        modality: text(&obj, tags::MODALITY).map_err(bad)?,
        transfer_syntax,
        rows: rows as usize,
        cols: cols as usize,
        pixel,
        frames,
        spacing_between_slices,
        slice_thickness: float(&obj, tags::SLICE_THICKNESS).map_err(bad)?,
    }))
}

/// True when the per-frame functional groups give each frame its own position.
fn has_per_frame_positions(obj: &InMemDicomObject) -> bool {
    obj.get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(|e| e.items())
        .is_some_and(|items| {
            items
                .iter()
                .any(|item| item.get(tags::PLANE_POSITION_SEQUENCE).is_some())
        })
}

/// A legacy multi-frame file (nuclear medicine, old ultrasound) gives the
/// position of its first frame only; the others follow along the normal,
/// SpacingBetweenSlices apart (the one place that attribute is used). Without
/// it, or without an orientation, the later frames stay unplaced and the
/// series is refused.
fn place_legacy_frames(frames: &mut [Frame], spacing_between_slices: Option<f64>) {
    let (Some(p), Some(o), Some(s)) = (
        frames[0].position,
        frames[0].orientation,
        spacing_between_slices.filter(|&s| s > 0.0),
    ) else {
        for f in frames.iter_mut().skip(1) {
            f.position = None;
        }
        return;
    };
    let Ok([_, _, n]) = super::series::axes(o) else {
        return;
    };
    for (k, f) in frames.iter_mut().enumerate() {
        f.position = Some([0, 1, 2].map(|i| p[i] + k as f64 * s * n[i]));
    }
}

fn pixel_format(obj: &InMemDicomObject) -> Result<PixelFormat, String> {
    let bits_allocated = int(obj, tags::BITS_ALLOCATED)?.ok_or("no BitsAllocated")?;
    if bits_allocated != 8 && bits_allocated != 16 {
        return Err(format!(
            "BitsAllocated {bits_allocated} is not supported (8 or 16)"
        ));
    }
    let bits_stored = int(obj, tags::BITS_STORED)?.unwrap_or(bits_allocated);
    let high_bit = int(obj, tags::HIGH_BIT)?.unwrap_or(bits_stored - 1);
    if !(1..=bits_allocated).contains(&bits_stored)
        || high_bit >= bits_allocated
        || high_bit + 1 < bits_stored
    {
        return Err(format!(
            "BitsStored {bits_stored} / HighBit {high_bit} do not fit BitsAllocated {bits_allocated}"
        ));
    }
    let signed = match int(obj, tags::PIXEL_REPRESENTATION)?.unwrap_or(0) {
        0 => false,
        1 => true,
        r => return Err(format!("PixelRepresentation {r} is not 0 or 1")),
    };
    Ok(PixelFormat {
        bits_allocated: bits_allocated as u16,
        bits_stored: bits_stored as u16,
        high_bit: high_bit as u16,
        signed,
    })
}

/// Position, orientation, spacing and rescale of frame `k`: from the
/// frame's item of the per-frame functional groups, else the shared
/// functional groups, else the top-level attributes (classic files).
fn frame(obj: &InMemDicomObject, k: usize, n_frames: usize) -> Result<Frame, String> {
    let per_frame = obj
        .get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE)
        .and_then(|e| e.items());
    if let Some(items) = per_frame
        && items.len() != n_frames
    {
        return Err(format!(
            "{} per-frame functional groups for {n_frames} frames",
            items.len()
        ));
    }
    let groups: Vec<&InMemDicomObject> = [
        per_frame.and_then(|items| items.get(k)),
        obj.get(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE)
            .and_then(|e| e.items())
            .and_then(|items| items.first()),
    ]
    .into_iter()
    .flatten()
    .collect();
    let lookup = |seq: Tag, attr: Tag| -> Result<Option<Vec<f64>>, String> {
        for g in &groups {
            if let Some(item) = g
                .get(seq)
                .and_then(|e| e.items())
                .and_then(|items| items.first())
                && let Some(v) = floats(item, attr)?
            {
                return Ok(Some(v));
            }
        }
        floats(obj, attr)
    };
    let fixed = |v: Option<Vec<f64>>, name: &str, n: usize| -> Result<Option<Vec<f64>>, String> {
        match v {
            Some(v) if v.len() != n => Err(format!("{name} has {} values, not {n}", v.len())),
            v => Ok(v),
        }
    };
    let position = fixed(
        lookup(tags::PLANE_POSITION_SEQUENCE, tags::IMAGE_POSITION_PATIENT)?,
        "ImagePositionPatient",
        3,
    )?
    .map(|v| [v[0], v[1], v[2]]);
    let orientation = fixed(
        lookup(
            tags::PLANE_ORIENTATION_SEQUENCE,
            tags::IMAGE_ORIENTATION_PATIENT,
        )?,
        "ImageOrientationPatient",
        6,
    )?
    .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]);
    let spacing = match lookup(tags::PIXEL_MEASURES_SEQUENCE, tags::PIXEL_SPACING)? {
        Some(v) => Some(v),
        None => floats(obj, tags::IMAGER_PIXEL_SPACING)?,
    };
    // PixelSpacing is (row spacing, column spacing): y first.
    let spacing = fixed(spacing, "PixelSpacing", 2)?.map(|v| [v[1], v[0]]);
    if let Some(s) = spacing
        && s.iter().any(|&x| x <= 0.0)
    {
        return Err(format!("PixelSpacing {:?} is not positive", [s[1], s[0]]));
    }
    let one = |attr: Tag, name: &str| -> Result<Option<f64>, String> {
        match lookup(tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE, attr)? {
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(v) => Err(format!("{name} has {} values, not 1", v.len())),
            None => Ok(None),
        }
    };
    let slope = one(tags::RESCALE_SLOPE, "RescaleSlope")?.unwrap_or(1.0);
    let intercept = one(tags::RESCALE_INTERCEPT, "RescaleIntercept")?.unwrap_or(0.0);
    if slope == 0.0 {
        return Err("RescaleSlope is 0".into());
    }
    Ok(Frame {
        position,
        orientation,
        spacing,
        slope,
        intercept,
    })
}

/// A trimmed text value ("" when absent).
fn text(obj: &InMemDicomObject, tag: Tag) -> Result<String, String> {
    match obj.get(tag) {
        None => Ok(String::new()),
        Some(e) => e
            .to_str()
            .map(|s| {
                s.trim_matches(|c: char| c == '\0' || c.is_whitespace())
                    .to_string()
            })
            .map_err(|err| format!("bad {tag}: {err}")),
    }
}

/// An integer value (IS, US, SS, UL...); `None` when absent or empty.
fn int(obj: &InMemDicomObject, tag: Tag) -> Result<Option<i64>, String> {
    match obj.get(tag) {
        None => Ok(None),
        Some(e) if e.is_empty() => Ok(None),
        Some(e) => e
            .to_int::<i64>()
            .map(Some)
            .map_err(|err| format!("bad {} {tag}: {err}", tag_name(tag))),
    }
}

/// One finite float (DS, FD...); `None` when absent or empty.
fn float(obj: &InMemDicomObject, tag: Tag) -> Result<Option<f64>, String> {
    Ok(floats(obj, tag)?.and_then(|v| v.first().copied()))
}

/// Finite floats (DS, FD, ... with several values); `None` when absent or empty.
fn floats(obj: &InMemDicomObject, tag: Tag) -> Result<Option<Vec<f64>>, String> {
    match obj.get(tag) {
        None => Ok(None),
        Some(e) if e.is_empty() => Ok(None),
        Some(e) => {
            let v = e
                .to_multi_float64()
                .map_err(|err| format!("bad {} {tag}: {err}", tag_name(tag)))?;
            if v.iter().any(|x| !x.is_finite()) {
                return Err(format!("{} {tag} is not finite", tag_name(tag)));
            }
            Ok(Some(v))
        }
    }
}

/// The keyword of a tag, for error messages.
fn tag_name(tag: Tag) -> &'static str {
    use dicom_core::dictionary::DataDictionary;
    dicom_dictionary_std::StandardDataDictionary
        .by_tag(tag)
        .map(|e| e.alias)
        .unwrap_or("attribute")
}
