//! PLY header: scalar types with their aliases, elements, properties, and the header parser.

use super::{PlyEncoding, PlyError};

/// A PLY scalar type (every name and alias of the format).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// `char` / `int8`.
    I8,
    /// `uchar` / `uint8`.
    U8,
    /// `short` / `int16`.
    I16,
    /// `ushort` / `uint16`.
    U16,
    /// `int` / `int32`.
    I32,
    /// `uint` / `uint32`.
    U32,
    /// `float` / `float32`.
    F32,
    /// `double` / `float64`.
    F64,
}

impl Scalar {
    /// The type named `name` (either spelling), or `None`.
    pub fn from_name(name: &str) -> Option<Scalar> {
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

    /// The classic name written in headers.
    pub fn name(self) -> &'static str {
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

    /// Size in bytes in binary bodies.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// True for `float` and `double`.
    pub fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// The type of a property: a scalar, or a list with its count and item types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropKind {
    /// One scalar value.
    Scalar(Scalar),
    /// A count followed by that many items.
    List {
        /// Type of the count.
        count: Scalar,
        /// Type of each item.
        item: Scalar,
    },
}

/// A property declared in the header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    /// Property name.
    pub name: String,
    /// Its type.
    pub kind: PropKind,
}

/// An element declared in the header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Element {
    /// Element name (`vertex`, `face`, or anything else).
    pub name: String,
    /// Declared number of records.
    pub count: usize,
    /// Properties in record order.
    pub props: Vec<Property>,
}

impl Element {
    /// Record size in bytes when every property is a scalar (binary bodies), else `None`.
    pub fn fixed_size(&self) -> Option<usize> {
        self.props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => Some(s.size()),
                PropKind::List { .. } => None,
            })
            .sum()
    }

    /// Smallest possible binary record size (lists counted as an empty list).
    pub fn min_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => s.size(),
                PropKind::List { count, .. } => count.size(),
            })
            .sum()
    }

    /// Index of the property named `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

/// A parsed PLY header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// Body encoding.
    pub encoding: PlyEncoding,
    /// Elements in body order.
    pub elements: Vec<Element>,
    /// `comment` and `obj_info` lines (without the keyword).
    pub comments: Vec<String>,
    /// Byte offset of the body (just after the `end_header` line).
    pub body_offset: usize,
    /// Number of header lines (line numbers of an ascii body continue from here).
    pub lines: usize,
}

/// The words after a header keyword.
type Words<'a> = std::str::SplitAsciiWhitespace<'a>;

fn syntax(line: usize, message: String) -> PlyError {
    PlyError::HeaderSyntax { line, message }
}

/// Parses the header at the start of `bytes`.
pub fn parse_header(bytes: &[u8]) -> Result<Header, PlyError> {
    if bytes.is_empty() {
        return Err(PlyError::Empty);
    }
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut comments = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(if line_no == 0 {
                PlyError::BadMagic
            } else {
                PlyError::HeaderNotTerminated { lines: line_no }
            });
        }
        let (raw, next) = split_line(bytes, pos);
        pos = next;
        line_no += 1;
        let line = String::from_utf8_lossy(raw);
        let line = line.trim_end_matches('\r');
        if line_no == 1 {
            if line.trim_end() != "ply" {
                return Err(PlyError::BadMagic);
            }
            continue;
        }
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword {
            "format" => encoding = Some(parse_format(words, line_no)?),
            "comment" | "obj_info" => {
                let text = line.trim_start()[keyword.len()..].trim();
                comments.push(text.to_string());
            }
            "element" => elements.push(parse_element(words, line_no, &elements)?),
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(syntax(line_no, "`property` before any `element`".into()));
                };
                let property = parse_property(words, line_no, element)?;
                element.props.push(property);
            }
            "end_header" => break,
            other => return Err(syntax(line_no, format!("unknown header keyword `{other}`"))),
        }
    }
    let encoding = encoding.ok_or(PlyError::MissingFormat)?;
    Ok(Header { encoding, elements, comments, body_offset: pos, lines: line_no })
}

/// The line starting at `pos` (without its `\n`) and the offset of the next one.
fn split_line(bytes: &[u8], pos: usize) -> (&[u8], usize) {
    let (line, adv) = next_line(&bytes[pos..]);
    (line, pos + adv)
}

/// The first line of `rest` (without its terminator) and the bytes it spans with the terminator.
/// Lines end with LF, CR LF or a lone CR (files saved with classic Mac line endings).
pub(crate) fn next_line(rest: &[u8]) -> (&[u8], usize) {
    match rest.iter().position(|&b| b == b'\n' || b == b'\r') {
        Some(i) if rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n') => (&rest[..i], i + 2),
        Some(i) => (&rest[..i], i + 1),
        None => (rest, rest.len()),
    }
}

/// `format <encoding> <version>`.
fn parse_format(mut words: Words<'_>, line_no: usize) -> Result<PlyEncoding, PlyError> {
    let (Some(fmt), version) = (words.next(), words.next()) else {
        return Err(syntax(line_no, "`format` needs a format and a version".into()));
    };
    let enc = match fmt {
        "ascii" => PlyEncoding::Ascii,
        "binary_little_endian" => PlyEncoding::BinaryLittleEndian,
        "binary_big_endian" => PlyEncoding::BinaryBigEndian,
        other => return Err(PlyError::UnsupportedFormat { format: other.to_string() }),
    };
    if let Some(v) = version {
        if v != "1.0" && v != "1" {
            return Err(PlyError::UnsupportedFormat { format: format!("{fmt} {v}") });
        }
    }
    Ok(enc)
}

/// `element <name> <count>`, which must not repeat an earlier element's name.
fn parse_element(mut words: Words<'_>, line_no: usize, elements: &[Element]) -> Result<Element, PlyError> {
    let (Some(name), Some(count)) = (words.next(), words.next()) else {
        return Err(syntax(line_no, "`element` needs a name and a count".into()));
    };
    let count: usize =
        count.parse().map_err(|_| syntax(line_no, format!("element `{name}` has an invalid count {count:?}")))?;
    if elements.iter().any(|e| e.name == name) {
        return Err(syntax(line_no, format!("element `{name}` is declared twice")));
    }
    Ok(Element { name: name.to_string(), count, props: Vec::new() })
}

/// `property <type> <name>` or `property list <count type> <item type> <name>` of `element`.
fn parse_property(mut words: Words<'_>, line_no: usize, element: &Element) -> Result<Property, PlyError> {
    let ty = words.next().unwrap_or("");
    let scalar = |name: &str| {
        Scalar::from_name(name).ok_or_else(|| PlyError::UnknownType { line: line_no, name: name.to_string() })
    };
    let (kind, name) = if ty == "list" {
        let (Some(c), Some(i), Some(n)) = (words.next(), words.next(), words.next()) else {
            return Err(syntax(line_no, "`property list` needs a count type, an item type and a name".into()));
        };
        let count = scalar(c)?;
        if count.is_float() {
            return Err(syntax(line_no, format!("list `{n}` has a floating-point count type `{c}`")));
        }
        (PropKind::List { count, item: scalar(i)? }, n)
    } else {
        let Some(n) = words.next() else {
            return Err(syntax(line_no, "`property` needs a type and a name".into()));
        };
        (PropKind::Scalar(scalar(ty)?), n)
    };
    if element.find(name).is_some() {
        return Err(syntax(line_no, format!("property `{name}` of element `{}` is declared twice", element.name)));
    }
    Ok(Property { name: name.to_string(), kind })
}
