//! Layered OpenEXR files, written and read with the `exr` crate: named
//! layers of named `f32` or `u32` channels, a data window anywhere inside
//! the display window (a tile of a larger image, or the whole of it), and
//! custom header attributes (text, integers, floats).
//!
//! One part (a single-part scan-line file, which every OpenEXR reader
//! opens), lossless ZIP compression. Layers follow the OpenEXR naming
//! convention: the channel `C` of layer `L` is stored as `L.C`, the
//! channels of the unnamed base layer (`""`) as plain `C`. Standard channel
//! names: `R`, `G`, `B` (and `A`) for colours, `Z` for depth, `X`, `Y`,
//! `Z` for vectors such as normals, `id` for integer identifiers.
//!
//! Written atomically as every output of prism (`crate::output`), with its
//! non-finite policy: `±∞` is stored as is, NaN as 0.

use crate::PixelBounds;
use crate::output::{OutputError, encode_into, invalid, write_atomic};
use ::exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes, IntegerBounds,
    Layer, LayerAttributes, ReadChannels, ReadLayers, SmallVec, Text, Vec2, WritableImage, read,
};
use std::collections::BTreeMap;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

/// The values of one channel, one per pixel of the data window, row by
/// row from its top.
#[derive(Clone, Debug, PartialEq)]
pub enum ExrSamples {
    /// 32-bit floats.
    F32(Vec<f32>),
    /// 32-bit unsigned integers (ids, counts).
    U32(Vec<u32>),
}

impl ExrSamples {
    /// Number of values.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::F32(v) => v.len(),
            Self::U32(v) => v.len(),
        }
    }

    /// Whether there are no values.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The floats, if this is a float channel.
    #[must_use]
    pub fn as_f32(&self) -> Option<&[f32]> {
        match self {
            Self::F32(v) => Some(v),
            Self::U32(_) => None,
        }
    }

    /// The integers, if this is an integer channel.
    #[must_use]
    pub fn as_u32(&self) -> Option<&[u32]> {
        match self {
            Self::U32(v) => Some(v),
            Self::F32(_) => None,
        }
    }
}

/// One channel of a layer.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrChannel {
    /// The name within its layer (`R`, `Z`, `id`, …); not empty, no `.`.
    pub name: String,
    /// The values.
    pub samples: ExrSamples,
}

impl ExrChannel {
    /// A float channel.
    #[must_use]
    pub fn f32(name: impl Into<String>, values: Vec<f32>) -> Self {
        Self { name: name.into(), samples: ExrSamples::F32(values) }
    }

    /// An integer channel.
    #[must_use]
    pub fn u32(name: impl Into<String>, values: Vec<u32>) -> Self {
        Self { name: name.into(), samples: ExrSamples::U32(values) }
    }
}

/// A named group of channels (`""`: the base layer, e.g. the beauty `R`,
/// `G`, `B`).
#[derive(Clone, Debug, PartialEq)]
pub struct ExrLayer {
    /// The layer's name (`""` for the base layer; may contain `.` for
    /// nested layers).
    pub name: String,
    /// Its channels.
    pub channels: Vec<ExrChannel>,
}

impl ExrLayer {
    /// The channel `name`, if the layer has it.
    #[must_use]
    pub fn channel(&self, name: &str) -> Option<&ExrSamples> {
        self.channels.iter().find(|c| c.name == name).map(|c| &c.samples)
    }
}

/// A custom header attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum ExrAttribute {
    /// Text (stored as UTF-8 bytes in an OpenEXR `string` attribute).
    Text(String),
    /// A 32-bit signed integer (`int`).
    Int(i32),
    /// A 32-bit float (`float`).
    Float(f32),
}

/// A layered OpenEXR image: a `width × height` display window at the
/// origin, and the pixels of its `data_window` in every channel.
#[derive(Clone, Debug, PartialEq)]
pub struct LayeredExr {
    /// Display window width (the whole image).
    pub width: u32,
    /// Display window height.
    pub height: u32,
    /// The pixels stored, inside the display window.
    pub data_window: PixelBounds,
    /// The layers, each with its channels.
    pub layers: Vec<ExrLayer>,
    /// Custom header attributes by name (names of the standard OpenEXR
    /// attributes, such as `channels` or `dataWindow`, are refused).
    pub attributes: BTreeMap<String, ExrAttribute>,
}

/// Header attributes the file format defines (or the `exr` crate writes
/// itself): a custom attribute may not take their names.
const RESERVED: [&str; 21] = [
    "channels",
    "compression",
    "dataWindow",
    "displayWindow",
    "lineOrder",
    "pixelAspectRatio",
    "screenWindowCenter",
    "screenWindowWidth",
    "name",
    "type",
    "version",
    "chunkCount",
    "tiles",
    "chromaticities",
    "timeCode",
    "owner",
    "comments",
    "capDate",
    "utcOffset",
    "maxSamplesPerPixel",
    "view",
];

impl LayeredExr {
    /// The layer `name`, if present.
    #[must_use]
    pub fn layer(&self, name: &str) -> Option<&ExrLayer> {
        self.layers.iter().find(|l| l.name == name)
    }

    /// The channel `channel` of layer `layer`, if present.
    #[must_use]
    pub fn channel(&self, layer: &str, channel: &str) -> Option<&ExrSamples> {
        self.layer(layer).and_then(|l| l.channel(channel))
    }

    /// The text attribute `name`, if present and text.
    #[must_use]
    pub fn text(&self, name: &str) -> Option<&str> {
        match self.attributes.get(name) {
            Some(ExrAttribute::Text(t)) => Some(t),
            _ => None,
        }
    }

    /// The integer attribute `name`, if present and an integer.
    #[must_use]
    pub fn int(&self, name: &str) -> Option<i32> {
        match self.attributes.get(name) {
            Some(ExrAttribute::Int(i)) => Some(*i),
            _ => None,
        }
    }
}

/// The name a channel has in the file: `layer.channel`, or `channel` in the
/// base layer.
fn file_channel_name(layer: &str, channel: &str) -> String {
    if layer.is_empty() { channel.to_owned() } else { format!("{layer}.{channel}") }
}

/// Writes `image` to `path`, atomically.
///
/// # Errors
/// [`OutputError::Invalid`] for an empty display window, a data window
/// outside it (or beyond `i32`), no channel, a channel without a name or
/// with a `.` in it, two channels of the same file name, a channel whose
/// length is not the data window's area, or a reserved or empty attribute
/// name; [`OutputError::Io`] or [`OutputError::Image`] if writing fails
/// (the target is then untouched).
pub fn write_layered_exr(path: &Path, image: &LayeredExr) -> Result<(), OutputError> {
    let dw = image.data_window;
    if image.width == 0 || image.height == 0 {
        return Err(invalid(path, format!("cannot write an empty {}×{} image", image.width, image.height)));
    }
    if dw.within(image.width, image.height).is_err() || i32::try_from(image.width.max(image.height)).is_err()
    {
        return Err(invalid(
            path,
            format!(
                "the data window {dw} does not lie inside the {}×{} display window",
                image.width, image.height
            ),
        ));
    }
    let area = dw.area() as usize;
    let mut names: Vec<String> = Vec::new();
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for layer in &image.layers {
        for c in &layer.channels {
            if c.name.is_empty() || c.name.contains('.') {
                return Err(invalid(
                    path,
                    format!(
                        "layer `{}`: channel name `{}` must be non-empty without `.`",
                        layer.name, c.name
                    ),
                ));
            }
            let full = file_channel_name(&layer.name, &c.name);
            if names.contains(&full) {
                return Err(invalid(path, format!("two channels are named `{full}`")));
            }
            if c.samples.len() != area {
                return Err(invalid(
                    path,
                    format!(
                        "channel `{full}` holds {} values; the data window {dw} has {area} pixels",
                        c.samples.len()
                    ),
                ));
            }
            let samples = match &c.samples {
                ExrSamples::F32(v) => {
                    FlatSamples::F32(v.iter().map(|&x| if x.is_nan() { 0.0 } else { x }).collect())
                }
                ExrSamples::U32(v) => FlatSamples::U32(v.clone()),
            };
            list.push(AnyChannel::new(Text::from_slice_unchecked(full.as_bytes()), samples));
            names.push(full);
        }
    }
    if list.is_empty() {
        return Err(invalid(path, "an OpenEXR file needs at least one channel"));
    }
    let mut attributes = LayerAttributes::default().with_position(Vec2(dw.x0() as i32, dw.y0() as i32));
    for (name, value) in &image.attributes {
        if name.is_empty() || RESERVED.contains(&name.as_str()) {
            return Err(invalid(path, format!("`{name}` cannot name a custom attribute")));
        }
        let value = match value {
            ExrAttribute::Text(t) => AttributeValue::Text(Text::from_slice_unchecked(t.as_bytes())),
            ExrAttribute::Int(i) => AttributeValue::I32(*i),
            ExrAttribute::Float(f) => AttributeValue::F32(*f),
        };
        attributes.other.insert(Text::from_slice_unchecked(name.as_bytes()), value);
    }
    let layer = Layer::new(
        Vec2(dw.width() as usize, dw.height() as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let display = IntegerBounds::from_dimensions(Vec2(image.width as usize, image.height as usize));
    let exr = Image::new(ImageAttributes::new(display), layer);
    write_atomic(path, |w| {
        encode_into(path, w, |w| exr.write().to_buffered(w))?;
        // The exr crate writes custom attributes in its hash map's order,
        // which changes from run to run; the same image should be the same
        // bytes. The header keeps its length, so it is sorted in place
        // where the file can be read back (not a pipe or a device).
        let io = |source| OutputError::Io { path: path.to_path_buf(), source };
        w.flush().map_err(io)?;
        let f = w.get_mut();
        if f.seek(SeekFrom::Start(0)).is_err() {
            return Ok(());
        }
        let mut head = Vec::new();
        let read = (&mut *f).take(HEADER_READ).read_to_end(&mut head).is_ok();
        if read && sort_header_attributes(&mut head) {
            f.seek(SeekFrom::Start(0)).map_err(io)?;
            f.write_all(&head).map_err(io)?;
        }
        f.seek(SeekFrom::End(0)).map_err(io)?;
        Ok(())
    })
}

/// How much of a written file is read back to find its header: prism's
/// headers take a few kilobytes (the tile's settings text the most).
const HEADER_READ: u64 = 1 << 20;

/// Puts the header attributes of a single-part OpenEXR file `b` (its
/// start, holding at least the header) in the order of their names, in
/// place, and says whether it did. The header keeps its length, so the
/// offsets after it stay right. Other files (multi-part, deep) and a
/// header that does not parse (or not within `b`) are left as they are.
fn sort_header_attributes(b: &mut [u8]) -> bool {
    let Some((mut spans, end)) = header_spans(b) else { return false };
    spans.sort_by(|x, y| b[x.0..x.1].cmp(&b[y.0..y.1]));
    let sorted: Vec<u8> = spans.iter().flat_map(|&(start, _, next)| b[start..next].to_vec()).collect();
    b[8..end].copy_from_slice(&sorted);
    true
}

/// One header attribute's bytes: `(start, end of its name, end)`.
type AttributeSpan = (usize, usize, usize);

/// The attributes of the header of a single-part OpenEXR file `b` (its
/// start), and where the header ends (its closing NUL); `None` for a
/// multi-part or deep file or a header that does not parse within `b`.
fn header_spans(b: &[u8]) -> Option<(Vec<AttributeSpan>, usize)> {
    const MULTIPART_OR_DEEP: u32 = 0x1000 | 0x800;
    let word =
        |at: usize| b.get(at..at + 4).and_then(|w| <[u8; 4]>::try_from(w).ok()).map(u32::from_le_bytes);
    if b.get(..4)? != EXR_MAGIC || word(4)? & MULTIPART_OR_DEEP != 0 {
        return None;
    }
    // Each attribute: name NUL, type NUL, a 4-byte size, the value; a NUL
    // where a name would start ends the header.
    let zero_from = |i: usize| b.get(i..)?.iter().position(|&c| c == 0).map(|n| i + n);
    let mut spans = Vec::new();
    let mut i = 8;
    while *b.get(i)? != 0 {
        let name_end = zero_from(i)?;
        let size = zero_from(name_end + 1)? + 1;
        let next = (size + 4).checked_add(word(size)? as usize)?;
        if next > b.len() {
            return None;
        }
        spans.push((i, name_end, next));
        i = next;
    }
    Some((spans, i))
}

/// The first four bytes of every OpenEXR file.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Reads a single-part OpenEXR file written by [`write_layered_exr`] (or
/// any single-part scan-line or tiled file whose display window starts at
/// the origin). Channels are grouped into layers by the part of their name
/// before the last `.`; layers and channels come in the file's order
/// (alphabetical). Half-float channels are widened to `f32`. Attributes
/// other than text, `int` and `float` ones are left out.
///
/// # Errors
/// [`OutputError::Read`] if the file cannot be read, [`OutputError::Image`]
/// if it is not a readable OpenEXR file, has several parts, a display
/// window away from the origin, or a data window outside it.
pub fn read_layered_exr(path: &Path) -> Result<LayeredExr, OutputError> {
    let bad = |reason: String| OutputError::Image { path: path.to_path_buf(), reason };
    let read_error = |source| OutputError::Read { path: path.to_path_buf(), source };
    let mut file = std::fs::File::open(path).map_err(read_error)?;
    // The magic number first, so that another kind of file (a PNG given
    // to `prism merge`) is named as such, not by the decoder's words.
    let mut magic = [0u8; 4];
    match file.read_exact(&mut magic) {
        Ok(()) if magic == EXR_MAGIC => {}
        Ok(()) => {
            return Err(bad("not an OpenEXR file (it does not start with OpenEXR's magic number)".into()));
        }
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            return Err(bad("not an OpenEXR file (shorter than OpenEXR's 4-byte magic number)".into()));
        }
        Err(e) => return Err(read_error(e)),
    }
    file.seek(std::io::SeekFrom::Start(0)).map_err(read_error)?;
    let exr = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_unbuffered(file)
        .map_err(|e| match e {
            ::exr::error::Error::Io(source) => OutputError::Read { path: path.to_path_buf(), source },
            // The exr crate's words for an unexpected end of file (or an
            // offset past the end).
            ::exr::error::Error::Invalid(m) if m == "reference to missing bytes" => bad(
                "the file ends before the data its header promises (cut short, or not completely written?)"
                    .into(),
            ),
            other => bad(other.to_string()),
        })?;
    let [part] = exr.layer_data.as_slice() else {
        return Err(bad(format!("it has {} parts; prism reads single-part files", exr.layer_data.len())));
    };
    let display = exr.attributes.display_window;
    let (Ok(width), Ok(height)) = (u32::try_from(display.size.x()), u32::try_from(display.size.y())) else {
        return Err(bad("the display window is too large".into()));
    };
    if display.position != Vec2(0, 0) {
        let Vec2(x, y) = display.position;
        return Err(bad(format!("the display window starts at ({x}, {y}), not at the origin (0, 0)")));
    }
    let pos = part.attributes.layer_position;
    let window = u32::try_from(pos.x()).ok().zip(u32::try_from(pos.y()).ok()).and_then(|(x, y)| {
        let w = u32::try_from(part.size.x()).ok()?;
        let h = u32::try_from(part.size.y()).ok()?;
        PixelBounds::new(x, x.checked_add(w)?, y, y.checked_add(h)?).ok()?.within(width, height).ok()
    });
    let data_window = window.ok_or_else(|| {
        bad(format!(
            "the data window (at {:?}, {:?} pixels) is not inside the {width}×{height} display window",
            pos, part.size
        ))
    })?;
    let mut layers: Vec<ExrLayer> = Vec::new();
    for c in &part.channel_data.list {
        let full = String::from_utf8_lossy(c.name.bytes()).into_owned();
        let (layer, name) = match full.rsplit_once('.') {
            Some((l, n)) => (l.to_owned(), n.to_owned()),
            None => (String::new(), full.clone()),
        };
        let samples = match &c.sample_data {
            FlatSamples::F16(v) => ExrSamples::F32(v.iter().map(|h| h.to_f32()).collect()),
            FlatSamples::F32(v) => ExrSamples::F32(v.clone()),
            FlatSamples::U32(v) => ExrSamples::U32(v.clone()),
        };
        let channel = ExrChannel { name, samples };
        match layers.iter_mut().find(|l| l.name == layer) {
            Some(l) => l.channels.push(channel),
            None => layers.push(ExrLayer { name: layer, channels: vec![channel] }),
        }
    }
    let mut attributes = BTreeMap::new();
    for (name, value) in exr.attributes.other.iter().chain(&part.attributes.other) {
        let value = match value {
            AttributeValue::Text(t) => ExrAttribute::Text(String::from_utf8_lossy(t.bytes()).into_owned()),
            AttributeValue::I32(i) => ExrAttribute::Int(*i),
            AttributeValue::F32(f) => ExrAttribute::Float(*f),
            _ => continue,
        };
        attributes.insert(String::from_utf8_lossy(name.bytes()).into_owned(), value);
    }
    Ok(LayeredExr { width, height, data_window, layers, attributes })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_image() -> LayeredExr {
        let dw = PixelBounds::new(3, 7, 2, 5).unwrap();
        let n = dw.area() as usize;
        let ramp = |k: f32| (0..n).map(|i| i as f32 * k).collect::<Vec<f32>>();
        let mut beauty = ramp(0.25);
        beauty[1] = f32::INFINITY;
        let mut attributes = BTreeMap::new();
        attributes.insert("prism:scene".to_owned(), ExrAttribute::Text("scènes/seed.toml".into()));
        attributes.insert("prism:spp".to_owned(), ExrAttribute::Int(16));
        attributes.insert("prism:scale".to_owned(), ExrAttribute::Float(0.5));
        LayeredExr {
            width: 10,
            height: 6,
            data_window: dw,
            layers: vec![
                ExrLayer {
                    name: String::new(),
                    channels: vec![
                        ExrChannel::f32("R", beauty),
                        ExrChannel::f32("G", ramp(-1.0)),
                        ExrChannel::f32("B", ramp(3.0)),
                    ],
                },
                ExrLayer { name: "depth".into(), channels: vec![ExrChannel::f32("Z", ramp(1.5))] },
                ExrLayer {
                    name: "object_id".into(),
                    channels: vec![ExrChannel::u32(
                        "id",
                        (0..n as u32).map(|i| i * 7 + u32::MAX / 2).collect(),
                    )],
                },
            ],
            attributes,
        }
    }

    #[test]
    fn layers_data_window_and_attributes_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("tile.exr");
        let img = sample_image();
        write_layered_exr(&p, &img).unwrap();
        let back = read_layered_exr(&p).unwrap();
        assert_eq!((back.width, back.height, back.data_window), (10, 6, img.data_window));
        assert_eq!(back.attributes, img.attributes);
        // The same image is the same bytes: the header's attributes are in
        // the order of their names, whatever order the exr crate's hash map
        // gave them.
        let bytes = std::fs::read(&p).unwrap();
        let (spans, _) = header_spans(&bytes).unwrap();
        let name = |&(start, name_end, _): &AttributeSpan| {
            String::from_utf8(bytes[start..name_end].to_vec()).unwrap()
        };
        let names: Vec<String> = spans.iter().map(name).collect();
        assert!(
            names.contains(&"prism:spp".to_owned()) && names.contains(&"dataWindow".to_owned()),
            "{names:?}"
        );
        assert!(names.is_sorted(), "{names:?}");
        for _ in 0..4 {
            write_layered_exr(&p, &img).unwrap();
            assert_eq!(std::fs::read(&p).unwrap(), bytes);
        }
        for layer in &img.layers {
            for c in &layer.channels {
                assert_eq!(back.channel(&layer.name, &c.name), Some(&c.samples), "{}.{}", layer.name, c.name);
            }
        }
        assert_eq!(back.layers.len(), 3);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "no temporary file is left");

        // Read with the exr crate directly: the data window, the file's channel names and types.
        let raw = ::exr::prelude::read_first_flat_layer_from_file(&p).unwrap();
        assert_eq!(raw.attributes.display_window.size, Vec2(10, 6));
        assert_eq!(raw.layer_data.attributes.layer_position, Vec2(3, 2));
        assert_eq!(raw.layer_data.size, Vec2(4, 3));
        let names: Vec<String> =
            raw.layer_data.channel_data.list.iter().map(|c| c.name.to_string()).collect();
        assert_eq!(names, ["B", "G", "R", "depth.Z", "object_id.id"]);
        let id = &raw.layer_data.channel_data.list[4].sample_data;
        assert!(matches!(id, FlatSamples::U32(v) if v[2] == 14 + u32::MAX / 2));
        let spp = raw.layer_data.attributes.other.get(&Text::from("prism:spp"));
        assert_eq!(spp, Some(&AttributeValue::I32(16)));
    }

    #[test]
    fn nan_is_stored_as_zero() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.exr");
        let mut img = sample_image();
        img.layers.truncate(1);
        img.layers[0].channels.truncate(1);
        img.layers[0].channels[0] = ExrChannel::f32("R", vec![f32::NAN; 12]);
        write_layered_exr(&p, &img).unwrap();
        assert_eq!(read_layered_exr(&p).unwrap().channel("", "R"), Some(&ExrSamples::F32(vec![0.0; 12])));
    }

    #[test]
    fn malformed_images_are_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.exr");
        let check = |img: LayeredExr, want: &str| {
            let e = write_layered_exr(&p, &img).unwrap_err().to_string();
            assert!(e.contains(want), "{e}");
            assert!(!p.exists());
        };
        let mut outside = sample_image();
        outside.width = 6;
        check(outside, "does not lie inside the 6×6 display window");
        let mut short = sample_image();
        short.layers[1].channels[0] = ExrChannel::f32("Z", vec![0.0; 5]);
        check(short, "channel `depth.Z` holds 5 values; the data window 3,7,2,5 has 12 pixels");
        let mut dup = sample_image();
        dup.layers[1].name = String::new();
        dup.layers[1].channels[0].name = "R".into();
        check(dup, "two channels are named `R`");
        let mut dotted = sample_image();
        dotted.layers[1].channels[0].name = "a.b".into();
        check(dotted, "channel name `a.b` must be non-empty without `.`");
        let mut reserved = sample_image();
        reserved.attributes.insert("dataWindow".into(), ExrAttribute::Int(1));
        check(reserved, "`dataWindow` cannot name a custom attribute");
        let mut none = sample_image();
        none.layers.clear();
        check(none, "at least one channel");
        // Not an EXR file.
        std::fs::write(&p, b"not an exr").unwrap();
        let e = read_layered_exr(&p).unwrap_err();
        assert!(matches!(e, OutputError::Image { .. }), "{e}");
        assert!(
            e.to_string().ends_with(": not an OpenEXR file (it does not start with OpenEXR's magic number)"),
            "{e}"
        );
        std::fs::write(&p, b"v/").unwrap();
        assert!(read_layered_exr(&p).unwrap_err().to_string().contains("shorter than"));
        // Cut short anywhere past its header: said so, not in the exr
        // crate's words ("invalid: reference to missing bytes").
        write_layered_exr(&p, &sample_image()).unwrap();
        let whole = std::fs::read(&p).unwrap();
        for keep in [whole.len() / 2, whole.len() - 1] {
            std::fs::write(&p, &whole[..keep]).unwrap();
            let e = read_layered_exr(&p).unwrap_err().to_string();
            assert!(e.ends_with("the file ends before the data its header promises (cut short, or not completely written?)"), "{keep}: {e}");
        }
        // The magic number alone passes the check and fails in the decoder.
        std::fs::write(&p, EXR_MAGIC).unwrap();
        assert!(matches!(read_layered_exr(&p), Err(OutputError::Image { .. })));
        assert!(matches!(read_layered_exr(&dir.path().join("missing.exr")), Err(OutputError::Read { .. })));
    }
}
