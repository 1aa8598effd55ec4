//! PLY reader (Greg Turk's polygon file format, as documented in "The PLY
//! Polygon File Format", Stanford 1994, and by Paul Bourke): ASCII,
//! binary little-endian and binary big-endian bodies.
//!
//! Read: element `vertex` with scalar properties `x`, `y`, `z`, optional
//! `nx`, `ny`, `nz` (all three or ignored) and optional texture coordinates
//! `u`/`v`, `s`/`t`, `texture_u`/`texture_v` or `texture_s`/`texture_t`
//! (the first complete pair); element `face` with a list property
//! `vertex_indices` or `vertex_index`. Every PLY scalar type is accepted
//! for every property (`char uchar short ushort int uint float double` and
//! the aliases `int8 uint8 int16 uint16 int32 uint32 float32 float64`);
//! values are converted to `f32` (positions, normals, uvs) or checked
//! against the vertex count (indices, which must have an integer type).
//! Polygons are triangulated as fans `(v0, v1, v2), (v0, v2, v3), ...`;
//! faces with fewer than three vertices are skipped. Every other element
//! and property (lists included) is skipped; so is anything after the last
//! declared element. `comment` and `obj_info` header lines are ignored, and
//! so are unknown lines before the first `element` (Blender 2.4x's
//! exporter writes an uncommented "Created by Blender" line there).
//!
//! ASCII bodies hold one element per line (blank lines are skipped), values
//! separated by whitespace; integer properties must be written as integers
//! within their type's range.
//!
//! Before anything is allocated, the header's counts are checked against
//! the bytes after the header: at least the fixed part of each element in
//! binary files (lists counted as their length field alone), at least two
//! bytes per property (a digit and a separator) in ASCII files.

use std::path::Path;

use crate::{MeshData, MeshError};

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// Inclusive range of an integer type.
    fn int_range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => (i64::MIN, i64::MAX),
        }
    }

    /// Decodes `bytes` (exactly `self.size()` long) in the given byte order.
    /// Every value of every type is exact in `f64`.
    fn decode(self, bytes: &[u8], big: bool) -> f64 {
        macro_rules! get {
            ($t:ty) => {{
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(bytes);
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(get!(i8)),
            Scalar::U8 => f64::from(get!(u8)),
            Scalar::I16 => f64::from(get!(i16)),
            Scalar::U16 => f64::from(get!(u16)),
            Scalar::I32 => f64::from(get!(i32)),
            Scalar::U32 => f64::from(get!(u32)),
            Scalar::F32 => f64::from(get!(f32)),
            Scalar::F64 => get!(f64),
        }
    }
}

/// The type of a property: one scalar, or a list with its length type.
#[derive(Debug, Clone, Copy)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    kind: Kind,
    /// 1-based header line, for errors.
    line: usize,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
    line: usize,
}

impl Element {
    /// Smallest number of body bytes one instance takes: binary, every
    /// scalar and every list's length field; ASCII, one character and one
    /// separator per property.
    fn min_row_bytes(&self, format: Format) -> u64 {
        match format {
            Format::Ascii => 2 * self.props.len() as u64,
            _ => self
                .props
                .iter()
                .map(|p| match p.kind {
                    Kind::Scalar(s) => s.size() as u64,
                    Kind::List { count, .. } => count.size() as u64,
                })
                .sum(),
        }
    }

    fn has_lists(&self) -> bool {
        self.props.iter().any(|p| matches!(p.kind, Kind::List { .. }))
    }

    /// "vertices", "faces", or "`name` elements", for messages.
    fn plural(&self) -> String {
        match self.name.as_str() {
            "vertex" => "vertices".into(),
            "face" => "faces".into(),
            other => format!("{other:?} elements"),
        }
    }
}

/// The encoding of a PLY body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

/// A parsed PLY header.
#[derive(Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body (just after the `end_header` line).
    body_start: usize,
    /// Number of header lines, so that ASCII body line numbers continue.
    lines: usize,
}

/// What a property is used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Position(usize),
    Normal(usize),
    Uv(usize),
    Indices,
    Skip,
}

/// Reads a PLY file (ASCII or binary) into a [`MeshData`]; see the module
/// documentation for what is read. The whole file is read into memory
/// first; [`crate::estimate_mesh_bytes`] says how much that takes.
pub fn read_ply(path: impl AsRef<Path>) -> Result<MeshData, MeshError> {
    let path = path.as_ref();
    let data = crate::read_file(path)?;
    parse_ply(&data, path)
}

/// Parses PLY bytes already in memory; `path` is only used in error
/// messages.
///
/// ```
/// use std::path::Path;
/// let ply = b"ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n\
///             property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n";
/// let err = niebla_mesh::parse_ply(ply, Path::new("lying.ply")).unwrap_err();
/// assert_eq!(
///     err.to_string(),
///     "lying.ply: file too short: the header declares 1000000000 vertices of at least 6 bytes each \
///      (as text) but only 6 bytes follow the header"
/// );
/// ```
pub fn parse_ply(data: &[u8], path: &Path) -> Result<MeshData, MeshError> {
    let header = parse_header(data, path)?;
    let body = data.get(header.body_start..).unwrap_or(&[]);
    check_declared_sizes(&header, body.len(), path)?;
    let (vertex, face) = find_mesh_elements(&header, path)?;
    let roles = assign_roles(&header, vertex, face, path)?;
    let vertex_count = header.elements[vertex].count;
    let vertex_count_u32 = u32::try_from(vertex_count).map_err(|_| MeshError::Header {
        path: path.to_path_buf(),
        line: header.elements[vertex].line,
        what: format!("{vertex_count} vertices; at most {} can be indexed", u32::MAX),
    })?;
    let mut out = Builder::new(&header, vertex, face, &roles);
    match header.format {
        Format::Ascii => {
            let mut src = AsciiBody::new(body, header.lines, path);
            read_elements(&mut src, &header, &roles, vertex_count_u32, &mut out)?;
        }
        format => {
            let big = format == Format::BinaryBigEndian;
            let mut src = BinaryBody::new(body, header.body_start, big, path);
            read_elements(&mut src, &header, &roles, vertex_count_u32, &mut out)?;
        }
    }
    if out.indices.is_empty() {
        return Err(MeshError::Invalid {
            origin: path.display().to_string(),
            what: "no triangles (faces with fewer than 3 vertices are skipped)".into(),
        });
    }
    MeshData::from_arrays(out.positions, out.indices, out.normals, out.uvs)
        .map_err(|e| e.with_origin(path.display().to_string()))
}

/// The memory estimate of [`crate::estimate_mesh_bytes`] for a PLY file of
/// `file_size` bytes whose first bytes (at least the whole header) are
/// `head`.
pub(crate) fn estimate_ply_bytes(head: &[u8], file_size: u64, path: &Path) -> Result<u64, MeshError> {
    let header = parse_header(head, path)?;
    let (vertex, face) = find_mesh_elements(&header, path)?;
    let roles = assign_roles(&header, vertex, face, path)?;
    let v = header.elements[vertex].count;
    let has = |f: fn(&Role) -> bool| roles[vertex].iter().any(f);
    let per_vertex = 12
        + if has(|r| matches!(r, Role::Normal(_))) { 12 } else { 0 }
        + if has(|r| matches!(r, Role::Uv(_))) { 8 } else { 0 };
    let faces = header.elements[face].count;
    // Binary files whose only variable-size data is the face index list give
    // the exact index count: the bytes left for the lists divided by the
    // index size. Otherwise (ASCII, other lists) every face counts as one
    // triangle.
    let mut triangles = faces;
    if header.format != Format::Ascii {
        let others_fixed = header.elements.iter().enumerate().all(|(i, e)| i == face || !e.has_lists());
        let face_lists = header.elements[face].props.iter().filter(|p| matches!(p.kind, Kind::List { .. })).count();
        let body = file_size.saturating_sub(header.body_start as u64);
        if others_fixed && face_lists == 1 {
            let fixed: u64 = header
                .elements
                .iter()
                .map(|e| e.count.saturating_mul(e.min_row_bytes(header.format)))
                .fold(0u64, u64::saturating_add);
            let item = roles[face]
                .iter()
                .zip(&header.elements[face].props)
                .find_map(|(r, p)| match (r, p.kind) {
                    (Role::Indices, Kind::List { item, .. }) => Some(item.size() as u64),
                    _ => None,
                })
                .unwrap_or(4);
            let items = body.saturating_sub(fixed) / item;
            triangles = items.saturating_sub(faces.saturating_mul(2)).max(faces);
        }
    }
    Ok(file_size.saturating_add(v.saturating_mul(per_vertex)).saturating_add(triangles.saturating_mul(12)))
}

fn header_error(path: &Path, line: usize, what: impl Into<String>) -> MeshError {
    MeshError::Header { path: path.to_path_buf(), line, what: what.into() }
}

/// Splits the header into lines (`\n` or `\r\n`) and parses them, up to and
/// including `end_header`.
fn parse_header(data: &[u8], path: &Path) -> Result<Header, MeshError> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format: Option<Format> = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= data.len() {
            return Err(if line_no == 0 {
                header_error(path, 1, "empty file; a PLY file starts with the line \"ply\"")
            } else {
                MeshError::Truncated {
                    path: path.to_path_buf(),
                    what: format!("the header ends after {line_no} lines without an \"end_header\" line"),
                }
            });
        }
        let end = data[pos..].iter().position(|&b| b == b'\n').map_or(data.len(), |i| pos + i);
        let raw = &data[pos..end];
        let next = if end < data.len() { end + 1 } else { end };
        line_no += 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if line_no == 1 {
            if raw.trim_ascii_end() != b"ply" {
                let shown: String = String::from_utf8_lossy(&raw[..raw.len().min(40)]).into();
                return Err(header_error(
                    path,
                    1,
                    format!("not a PLY file: the first line is {shown:?}, expected \"ply\""),
                ));
            }
            pos = next;
            continue;
        }
        let keyword = raw.split(|b| b.is_ascii_whitespace()).find(|w| !w.is_empty()).unwrap_or(b"");
        if keyword == b"comment" || keyword == b"obj_info" || keyword.is_empty() {
            pos = next;
            continue;
        }
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(header_error(path, line_no, "not ASCII text"));
        };
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        match words[0] {
            "format" => {
                if format.is_some() {
                    return Err(header_error(path, line_no, "a second \"format\" line"));
                }
                let f = match words.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::BinaryLittleEndian,
                    Some("binary_big_endian") => Format::BinaryBigEndian,
                    other => {
                        return Err(header_error(
                            path,
                            line_no,
                            format!(
                                "format {:?}; expected ascii, binary_little_endian or binary_big_endian",
                                other.unwrap_or("")
                            ),
                        ))
                    }
                };
                match words.get(2).copied() {
                    Some("1.0") | Some("1") if words.len() == 3 => {}
                    _ => {
                        return Err(header_error(
                            path,
                            line_no,
                            format!("expected \"format {} 1.0\", found {text:?}", words[1]),
                        ))
                    }
                }
                format = Some(f);
            }
            "element" => {
                let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
                    return Err(header_error(
                        path,
                        line_no,
                        format!("expected \"element <name> <count>\", found {text:?}"),
                    ));
                };
                let Ok(count) = count.parse::<u64>() else {
                    return Err(header_error(
                        path,
                        line_no,
                        format!("element {name}: count {count:?} is not a non-negative integer"),
                    ));
                };
                if elements.iter().any(|e| e.name == *name) {
                    return Err(header_error(path, line_no, format!("element {name:?} declared twice")));
                }
                elements.push(Element { name: (*name).into(), count, props: Vec::new(), line: line_no });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(header_error(path, line_no, "a property before any element"));
                };
                let bad_type = |t: &str| {
                    header_error(
                        path,
                        line_no,
                        format!(
                            "unknown type {t:?}; expected char, uchar, short, ushort, int, uint, float, double \
                             or int8, uint8, int16, uint16, int32, uint32, float32, float64"
                        ),
                    )
                };
                let property = match words.as_slice() {
                    ["property", "list", count, item, name] => {
                        let count_type = Scalar::from_name(count).ok_or_else(|| bad_type(count))?;
                        let item = Scalar::from_name(item).ok_or_else(|| bad_type(item))?;
                        if !count_type.is_integer() {
                            return Err(header_error(
                                path,
                                line_no,
                                format!("list {name}: length type {count} is not an integer type"),
                            ));
                        }
                        Property { name: (*name).into(), kind: Kind::List { count: count_type, item }, line: line_no }
                    }
                    ["property", "list", ..] => {
                        return Err(header_error(
                            path,
                            line_no,
                            format!("expected \"property list <length type> <item type> <name>\", found {text:?}"),
                        ))
                    }
                    ["property", ty, name] => Property {
                        name: (*name).into(),
                        kind: Kind::Scalar(Scalar::from_name(ty).ok_or_else(|| bad_type(ty))?),
                        line: line_no,
                    },
                    _ => {
                        return Err(header_error(
                            path,
                            line_no,
                            format!("expected \"property <type> <name>\", found {text:?}"),
                        ))
                    }
                };
                element.props.push(property);
            }
            "end_header" => {
                let Some(format) = format else {
                    return Err(header_error(path, line_no, "end_header before any \"format\" line"));
                };
                return Ok(Header { format, elements, body_start: next, lines: line_no });
            }
            // Blender 2.4x writes an uncommented "Created by Blender ..." line
            // after the format line: unknown lines before the first element
            // are read as comments. Later, where a misspelled keyword would
            // change how the body is read, they are errors.
            _ if elements.is_empty() => {}
            other => {
                return Err(header_error(
                    path,
                    line_no,
                    format!(
                        "unknown keyword {other:?}; expected format, comment, obj_info, element, property or \
                         end_header"
                    ),
                ))
            }
        }
        pos = next;
    }
}

/// Fails, before anything is allocated, when the body is shorter than the
/// smallest body the header's counts allow.
fn check_declared_sizes(header: &Header, body_len: usize, path: &Path) -> Result<(), MeshError> {
    let mut total: Option<u64> = Some(0);
    for e in &header.elements {
        let row = e.min_row_bytes(header.format);
        total = total.and_then(|t| e.count.checked_mul(row).and_then(|b| t.checked_add(b)));
    }
    // The last ASCII line may lack its newline.
    let needed = match (total, header.format) {
        (Some(t), Format::Ascii) => Some(t.saturating_sub(1)),
        (t, _) => t,
    };
    if needed.is_some_and(|n| n <= body_len as u64) {
        return Ok(());
    }
    let parts: Vec<String> = header
        .elements
        .iter()
        .filter(|e| e.count > 0 && !e.props.is_empty())
        .map(|e| {
            let at_least = if header.format == Format::Ascii || e.has_lists() { "at least " } else { "" };
            format!("{} {} of {at_least}{} bytes each", e.count, e.plural(), e.min_row_bytes(header.format))
        })
        .collect();
    let text = if header.format == Format::Ascii { " (as text)" } else { "" };
    Err(MeshError::Truncated {
        path: path.to_path_buf(),
        what: format!("the header declares {}{text} but only {body_len} bytes follow the header", parts.join(" and ")),
    })
}

/// Indices of the `vertex` and `face` elements.
fn find_mesh_elements(header: &Header, path: &Path) -> Result<(usize, usize), MeshError> {
    let find = |name: &str| header.elements.iter().position(|e| e.name == name);
    let vertex = find("vertex").ok_or_else(|| {
        header_error(path, header.lines, "the header declares no \"vertex\" element; a mesh needs one")
    })?;
    let face = find("face").ok_or_else(|| {
        header_error(
            path,
            header.lines,
            "the header declares no \"face\" element (a point cloud, not a mesh); a mesh needs one",
        )
    })?;
    Ok((vertex, face))
}

/// The role of every property of every element.
fn assign_roles(header: &Header, vertex: usize, face: usize, path: &Path) -> Result<Vec<Vec<Role>>, MeshError> {
    let mut roles: Vec<Vec<Role>> = header.elements.iter().map(|e| vec![Role::Skip; e.props.len()]).collect();
    let scalar = |e: &Element, name: &str| -> Result<Option<usize>, MeshError> {
        match e.props.iter().position(|p| p.name == name) {
            None => Ok(None),
            Some(i) => match e.props[i].kind {
                Kind::Scalar(_) => Ok(Some(i)),
                Kind::List { .. } => Err(header_error(
                    path,
                    e.props[i].line,
                    format!("vertex property {name:?} is a list; expected a scalar"),
                )),
            },
        }
    };
    let v = &header.elements[vertex];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let i = scalar(v, name)?.ok_or_else(|| {
            header_error(path, v.line, format!("element vertex has no property {name:?}; expected x, y and z"))
        })?;
        roles[vertex][i] = Role::Position(k);
    }
    let normal: Vec<Option<usize>> = ["nx", "ny", "nz"].iter().map(|n| scalar(v, n)).collect::<Result<_, _>>()?;
    if let [Some(a), Some(b), Some(c)] = normal[..] {
        for (k, i) in [a, b, c].into_iter().enumerate() {
            roles[vertex][i] = Role::Normal(k);
        }
    }
    for (u, w) in [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")] {
        if let (Some(a), Some(b)) = (scalar(v, u)?, scalar(v, w)?) {
            roles[vertex][a] = Role::Uv(0);
            roles[vertex][b] = Role::Uv(1);
            break;
        }
    }
    let f = &header.elements[face];
    let Some(i) = f.props.iter().position(|p| p.name == "vertex_indices" || p.name == "vertex_index") else {
        return Err(header_error(path, f.line, "element face has no property \"vertex_indices\" or \"vertex_index\""));
    };
    match f.props[i].kind {
        Kind::List { item, .. } if item.is_integer() => roles[face][i] = Role::Indices,
        Kind::List { item, .. } => {
            return Err(header_error(
                path,
                f.props[i].line,
                format!("face {}: index type {} is not an integer type", f.props[i].name, item.name()),
            ))
        }
        Kind::Scalar(_) => {
            return Err(header_error(
                path,
                f.props[i].line,
                format!("face {} is a scalar; expected a list (property list uchar int ...)", f.props[i].name),
            ))
        }
    }
    Ok(roles)
}

/// The arrays being filled.
struct Builder {
    positions: Vec<[f32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
    indices: Vec<[u32; 3]>,
}

impl Builder {
    /// Capacities come from the declared counts, which
    /// [`check_declared_sizes`] has bounded by the body's length.
    fn new(header: &Header, vertex: usize, face: usize, roles: &[Vec<Role>]) -> Builder {
        let n = usize::try_from(header.elements[vertex].count).unwrap_or(0);
        let f = usize::try_from(header.elements[face].count).unwrap_or(0);
        let has = |want: fn(&Role) -> bool| roles[vertex].iter().any(want);
        Builder {
            positions: Vec::with_capacity(n),
            normals: has(|r| matches!(r, Role::Normal(_))).then(|| Vec::with_capacity(n)),
            uvs: has(|r| matches!(r, Role::Uv(_))).then(|| Vec::with_capacity(n)),
            indices: Vec::with_capacity(f),
        }
    }
}

/// A source of values: the ASCII or binary body.
trait Body {
    /// Moves to instance `index` of element `element`.
    fn start_row(&mut self, element: &str, index: u64, declared: u64) -> Result<(), MeshError>;
    /// Reads one value of type `ty` for property `property`.
    fn scalar(&mut self, ty: Scalar, property: &str) -> Result<f64, MeshError>;
    /// Skips `n` values of type `ty` (a list's items).
    fn skip(&mut self, ty: Scalar, n: u64, property: &str) -> Result<(), MeshError>;
    /// Ends the current instance.
    fn end_row(&mut self) -> Result<(), MeshError>;
    /// An error at the current instance.
    fn error(&self, what: String) -> MeshError;
}

fn read_elements<B: Body>(
    src: &mut B,
    header: &Header,
    roles: &[Vec<Role>],
    vertex_count: u32,
    out: &mut Builder,
) -> Result<(), MeshError> {
    for (e, element) in header.elements.iter().enumerate() {
        if element.props.is_empty() {
            // Takes no bytes in any encoding.
            continue;
        }
        let roles = &roles[e];
        for index in 0..element.count {
            src.start_row(&element.name, index, element.count)?;
            let (mut p, mut n, mut uv) = ([0f32; 3], [0f32; 3], [0f32; 2]);
            let mut is_vertex = false;
            for (prop, &role) in element.props.iter().zip(roles) {
                match (prop.kind, role) {
                    // assign_roles gives Indices to lists only.
                    (Kind::Scalar(ty), Role::Skip | Role::Indices) => src.skip(ty, 1, &prop.name)?,
                    (Kind::Scalar(ty), Role::Position(k)) => {
                        p[k] = src.scalar(ty, &prop.name)? as f32;
                        is_vertex = true;
                    }
                    (Kind::Scalar(ty), Role::Normal(k)) => n[k] = src.scalar(ty, &prop.name)? as f32,
                    (Kind::Scalar(ty), Role::Uv(k)) => uv[k] = src.scalar(ty, &prop.name)? as f32,
                    (Kind::List { count, item }, role) => {
                        let len = src.scalar(count, &prop.name)?;
                        if len < 0.0 {
                            return Err(src.error(format!("{}: negative list length {len}", prop.name)));
                        }
                        let len = len as u64;
                        if role == Role::Indices {
                            read_polygon(src, item, len, &prop.name, vertex_count, &mut out.indices)?;
                        } else {
                            src.skip(item, len, &prop.name)?;
                        }
                    }
                }
            }
            src.end_row()?;
            if is_vertex {
                out.positions.push(p);
                if let Some(normals) = &mut out.normals {
                    normals.push(n);
                }
                if let Some(uvs) = &mut out.uvs {
                    uvs.push(uv);
                }
            }
        }
    }
    Ok(())
}

/// Reads a polygon's `len` indices and appends its fan triangulation.
fn read_polygon<B: Body>(
    src: &mut B,
    item: Scalar,
    len: u64,
    property: &str,
    vertex_count: u32,
    indices: &mut Vec<[u32; 3]>,
) -> Result<(), MeshError> {
    let mut first = 0u32;
    let mut prev = 0u32;
    for j in 0..len {
        let v = src.scalar(item, property)?;
        if v < 0.0 || v >= f64::from(vertex_count) {
            return Err(src.error(format!(
                "{property}[{j}]: vertex index {v} out of range (the file has {vertex_count} vertices)"
            )));
        }
        let v = v as u32;
        match j {
            0 => first = v,
            1 => {}
            _ => indices.push([first, prev, v]),
        }
        prev = v;
    }
    Ok(())
}

/// A binary body, little- or big-endian.
struct BinaryBody<'a> {
    data: &'a [u8],
    pos: usize,
    /// File offset of `data[0]`, for messages.
    base: usize,
    big: bool,
    path: &'a Path,
    element: String,
    index: u64,
    row_start: usize,
}

impl<'a> BinaryBody<'a> {
    fn new(data: &'a [u8], base: usize, big: bool, path: &'a Path) -> Self {
        BinaryBody { data, pos: 0, base, big, path, element: String::new(), index: 0, row_start: 0 }
    }

    fn truncated(&self, what: String) -> MeshError {
        MeshError::Truncated {
            path: self.path.to_path_buf(),
            what: format!(
                "{} {} (byte {}): the file ends at byte {} while reading {what}",
                self.element,
                self.index,
                self.base + self.row_start,
                self.base + self.data.len()
            ),
        }
    }
}

impl Body for BinaryBody<'_> {
    fn start_row(&mut self, element: &str, index: u64, _declared: u64) -> Result<(), MeshError> {
        if self.element != element {
            self.element = element.to_string();
        }
        self.index = index;
        self.row_start = self.pos;
        Ok(())
    }

    fn scalar(&mut self, ty: Scalar, property: &str) -> Result<f64, MeshError> {
        let size = ty.size();
        let Some(bytes) = self.data.get(self.pos..self.pos + size) else {
            return Err(self.truncated(format!("{property} ({})", ty.name())));
        };
        self.pos += size;
        Ok(ty.decode(bytes, self.big))
    }

    fn skip(&mut self, ty: Scalar, n: u64, property: &str) -> Result<(), MeshError> {
        let left = (self.data.len() - self.pos) as u64;
        match n.checked_mul(ty.size() as u64) {
            Some(bytes) if bytes <= left => {
                self.pos += bytes as usize;
                Ok(())
            }
            _ => Err(self.truncated(format!("{property} ({n} values of type {})", ty.name()))),
        }
    }

    fn end_row(&mut self) -> Result<(), MeshError> {
        Ok(())
    }

    fn error(&self, what: String) -> MeshError {
        MeshError::Parse {
            path: self.path.to_path_buf(),
            location: format!("{} {} (byte {})", self.element, self.index, self.base + self.row_start),
            what,
        }
    }
}

/// An ASCII body: one element instance per line.
struct AsciiBody<'a> {
    data: &'a [u8],
    pos: usize,
    /// 1-based line number of the current line.
    line: usize,
    path: &'a Path,
    element: String,
    index: u64,
    /// Token ranges of the current line, and the next one to read.
    tokens: Vec<(usize, usize)>,
    next: usize,
}

impl<'a> AsciiBody<'a> {
    fn new(data: &'a [u8], header_lines: usize, path: &'a Path) -> Self {
        AsciiBody {
            data,
            pos: 0,
            line: header_lines,
            path,
            element: String::new(),
            index: 0,
            tokens: Vec::new(),
            next: 0,
        }
    }

    fn token(&self, i: usize) -> &'a [u8] {
        let (a, b) = self.tokens[i];
        &self.data[a..b]
    }
}

impl Body for AsciiBody<'_> {
    fn start_row(&mut self, element: &str, index: u64, declared: u64) -> Result<(), MeshError> {
        if self.element != element {
            self.element = element.to_string();
        }
        self.index = index;
        loop {
            if self.pos >= self.data.len() {
                return Err(MeshError::Truncated {
                    path: self.path.to_path_buf(),
                    what: format!(
                        "the file ends after line {}, before {element} {index} (the header declares {declared})",
                        self.line
                    ),
                });
            }
            let end = self.data[self.pos..].iter().position(|&b| b == b'\n').map_or(self.data.len(), |i| self.pos + i);
            self.line += 1;
            self.tokens.clear();
            self.next = 0;
            let mut i = self.pos;
            while i < end {
                while i < end && self.data[i].is_ascii_whitespace() {
                    i += 1;
                }
                let start = i;
                while i < end && !self.data[i].is_ascii_whitespace() {
                    i += 1;
                }
                if i > start {
                    self.tokens.push((start, i));
                }
            }
            self.pos = end + 1;
            if !self.tokens.is_empty() {
                return Ok(());
            }
        }
    }

    fn scalar(&mut self, ty: Scalar, property: &str) -> Result<f64, MeshError> {
        if self.next >= self.tokens.len() {
            return Err(self.error(format!(
                "the line ends after {} values; expected a {} for property {property}",
                self.tokens.len(),
                ty.name()
            )));
        }
        let token = self.token(self.next);
        self.next += 1;
        let text = std::str::from_utf8(token).unwrap_or("");
        let value = match ty {
            Scalar::F32 => text.parse::<f32>().ok().map(f64::from),
            Scalar::F64 => text.parse::<f64>().ok(),
            _ => {
                let (lo, hi) = ty.int_range();
                text.parse::<i64>().ok().filter(|v| (lo..=hi).contains(v)).map(|v| v as f64)
            }
        };
        value.ok_or_else(|| {
            let shown = String::from_utf8_lossy(&token[..token.len().min(40)]).into_owned();
            let expected = if ty.is_integer() {
                let (lo, hi) = ty.int_range();
                format!("an integer in {lo}..={hi} ({})", ty.name())
            } else {
                format!("a number ({})", ty.name())
            };
            self.error(format!("property {property}: {shown:?} is not {expected}"))
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64, property: &str) -> Result<(), MeshError> {
        let left = (self.tokens.len() - self.next) as u64;
        if n > left {
            return Err(self.error(format!(
                "property {property}: expected {n} values of type {} but the line has {left} left",
                ty.name()
            )));
        }
        self.next += n as usize;
        Ok(())
    }

    fn end_row(&mut self) -> Result<(), MeshError> {
        if self.next < self.tokens.len() {
            return Err(self.error(format!(
                "{} values on the line but the header's properties take {}",
                self.tokens.len(),
                self.next
            )));
        }
        Ok(())
    }

    fn error(&self, what: String) -> MeshError {
        MeshError::Parse {
            path: self.path.to_path_buf(),
            location: format!("line {} ({} {})", self.line, self.element, self.index),
            what,
        }
    }
}
