//! A small XML element tree: what the exporters write, and a strict parser for the same subset
//! (elements, attributes in double or single quotes, comments, an XML declaration, the five
//! predefined entities and numeric character references), used to check that the output is
//! well-formed and to read it back in tests.
//!
//! Not a general XML parser: DTDs, CDATA sections and processing instructions other than the
//! declaration are refused as errors, never skipped.

use std::fmt::Write as _;

/// An element: tag, attributes in order, child elements. Text content is not modelled (the
/// formats written here have none); the parser accepts whitespace between elements only.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    pub tag: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
}

impl Element {
    pub fn new(tag: &str) -> Element {
        Element {
            tag: tag.to_string(),
            attrs: Vec::new(),
            children: Vec::new(),
        }
    }

    /// Adds an attribute (builder style).
    pub fn attr(mut self, name: &str, value: impl Into<String>) -> Element {
        self.attrs.push((name.to_string(), value.into()));
        self
    }

    /// Adds a child element (builder style).
    pub fn child(mut self, e: Element) -> Element {
        self.children.push(e);
        self
    }

    /// The value of attribute `name`, if present.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// Children with tag `tag`.
    pub fn children_named<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.tag == tag)
    }

    /// The first child with tag `tag` whose `name` attribute is `name` (Mitsuba's properties).
    pub fn property(&self, tag: &str, name: &str) -> Option<&Element> {
        self.children
            .iter()
            .find(|c| c.tag == tag && c.get("name") == Some(name))
    }

    /// Writes the element indented by `depth` levels of four spaces, one element per line.
    pub fn write(&self, out: &mut String, depth: usize) {
        let pad = "    ".repeat(depth);
        let _ = write!(out, "{pad}<{}", self.tag);
        for (k, v) in &self.attrs {
            let _ = write!(out, " {k}=\"{}\"", escape(v));
        }
        if self.children.is_empty() {
            out.push_str("/>\n");
        } else {
            out.push_str(">\n");
            for c in &self.children {
                c.write(out, depth + 1);
            }
            let _ = writeln!(out, "{pad}</{}>", self.tag);
        }
    }
}

/// Escapes the five XML special characters for use in an attribute value.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Text that is safe inside an XML comment: no `--` (forbidden there) and no trailing `-`.
pub fn comment_text(s: &str) -> String {
    let mut t = s.replace("--", "- -");
    while t.contains("--") {
        t = t.replace("--", "- -");
    }
    if t.ends_with('-') {
        t.push(' ');
    }
    t
}

/// Parses a document: an optional `<?xml ...?>` declaration, comments and whitespace, exactly
/// one root element, comments and whitespace. The error names the byte offset and the problem.
pub fn parse(text: &str) -> Result<Element, String> {
    let mut p = Parser {
        s: text.as_bytes(),
        i: 0,
    };
    p.skip_misc(true)?;
    if p.i >= p.s.len() {
        return Err("the document has no root element".into());
    }
    let root = p.element(0)?;
    p.skip_misc(false)?;
    if p.i != p.s.len() {
        return Err(p.err("content after the root element"));
    }
    Ok(root)
}

/// Nesting limit of the parser (the documents written here are a few levels deep).
const MAX_DEPTH: usize = 64;

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn err(&self, what: &str) -> String {
        format!("byte {}: {what}", self.i)
    }

    fn starts(&self, pat: &str) -> bool {
        self.s[self.i..].starts_with(pat.as_bytes())
    }

    fn skip_ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    /// Whitespace, comments and (at the start only) the XML declaration.
    fn skip_misc(&mut self, prolog: bool) -> Result<(), String> {
        let mut first = true;
        loop {
            if prolog && first && self.starts("<?xml") {
                match find(self.s, self.i, b"?>") {
                    Some(end) => self.i = end + 2,
                    None => return Err(self.err("unterminated XML declaration")),
                }
            }
            first = false;
            self.skip_ws();
            if self.starts("<!--") {
                self.comment()?;
            } else if self.starts("<?") || self.starts("<!") {
                return Err(self.err(
                    "processing instructions, DTDs and CDATA are not supported by this parser",
                ));
            } else {
                return Ok(());
            }
        }
    }

    fn comment(&mut self) -> Result<(), String> {
        let start = self.i + 4;
        match find(self.s, start, b"--") {
            Some(j) if self.s.get(j + 2) == Some(&b'>') => {
                self.i = j + 3;
                Ok(())
            }
            Some(_) => Err(self.err("\"--\" inside a comment")),
            None => Err(self.err("unterminated comment")),
        }
    }

    fn name(&mut self) -> Result<String, String> {
        let start = self.i;
        while self.i < self.s.len() {
            let c = self.s[self.i];
            let ok =
                c.is_ascii_alphanumeric() || matches!(c, b'_' | b':' | b'-' | b'.') || c >= 0x80;
            if !ok {
                break;
            }
            self.i += 1;
        }
        if self.i == start || self.s[start].is_ascii_digit() || matches!(self.s[start], b'-' | b'.')
        {
            return Err(self.err("expected a name"));
        }
        Ok(String::from_utf8_lossy(&self.s[start..self.i]).into_owned())
    }

    fn element(&mut self, depth: usize) -> Result<Element, String> {
        if depth > MAX_DEPTH {
            return Err(self.err("elements nested too deeply"));
        }
        if !self.starts("<") {
            return Err(self.err("expected '<'"));
        }
        self.i += 1;
        let tag = self.name()?;
        let mut e = Element::new(&tag);
        loop {
            let before = self.i;
            self.skip_ws();
            if self.starts("/>") {
                self.i += 2;
                return Ok(e);
            }
            if self.starts(">") {
                self.i += 1;
                break;
            }
            if self.i == before {
                return Err(self.err("expected whitespace, '>' or '/>'"));
            }
            let k = self.name()?;
            self.skip_ws();
            if !self.starts("=") {
                return Err(self.err(&format!("attribute {k} has no '='")));
            }
            self.i += 1;
            self.skip_ws();
            let q = *self
                .s
                .get(self.i)
                .ok_or_else(|| self.err("unexpected end"))?;
            if q != b'"' && q != b'\'' {
                return Err(self.err(&format!("attribute {k}: value must be quoted")));
            }
            let end = self.s[self.i + 1..]
                .iter()
                .position(|&c| c == q)
                .map(|p| p + self.i + 1)
                .ok_or_else(|| self.err(&format!("attribute {k}: unterminated value")))?;
            let raw = &self.s[self.i + 1..end];
            if raw.contains(&b'<') {
                return Err(self.err(&format!("attribute {k}: '<' in a value")));
            }
            let v = unescape(&String::from_utf8_lossy(raw)).map_err(|m| self.err(&m))?;
            if e.get(&k).is_some() {
                return Err(self.err(&format!("duplicate attribute {k}")));
            }
            e.attrs.push((k, v));
            self.i = end + 1;
        }
        // Content: child elements, comments and whitespace, then the matching end tag.
        loop {
            self.skip_ws();
            if self.i >= self.s.len() {
                return Err(self.err(&format!("element <{tag}> is not closed")));
            }
            if self.starts("</") {
                self.i += 2;
                let close = self.name()?;
                if close != tag {
                    return Err(self.err(&format!("</{close}> closes <{tag}>")));
                }
                self.skip_ws();
                if !self.starts(">") {
                    return Err(self.err("expected '>'"));
                }
                self.i += 1;
                return Ok(e);
            }
            if self.starts("<!--") {
                self.comment()?;
                continue;
            }
            if self.starts("<") {
                let c = self.element(depth + 1)?;
                e.children.push(c);
                continue;
            }
            return Err(self.err(&format!("text inside <{tag}> (not expected here)")));
        }
    }
}

fn find(s: &[u8], from: usize, pat: &[u8]) -> Option<usize> {
    if from > s.len() {
        return None;
    }
    s[from..]
        .windows(pat.len())
        .position(|w| w == pat)
        .map(|p| p + from)
}

fn unescape(s: &str) -> Result<String, String> {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(amp) = rest.find('&') {
        out.push_str(&rest[..amp]);
        let tail = &rest[amp..];
        let semi = tail
            .find(';')
            .ok_or_else(|| format!("unterminated entity in {s:?}"))?;
        let ent = &tail[1..semi];
        let c = match ent {
            "amp" => '&',
            "lt" => '<',
            "gt" => '>',
            "quot" => '"',
            "apos" => '\'',
            _ => {
                let code = if let Some(h) = ent.strip_prefix("#x") {
                    u32::from_str_radix(h, 16).ok()
                } else if let Some(d) = ent.strip_prefix('#') {
                    d.parse().ok()
                } else {
                    None
                };
                code.and_then(char::from_u32)
                    .ok_or_else(|| format!("unknown entity &{ent}; in {s:?}"))?
            }
        };
        out.push(c);
        rest = &tail[semi + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_with_escapes() {
        let e = Element::new("scene")
            .attr("version", "3.0.0")
            .child(Element::new("string").attr("value", "a<b & \"c\" 'd'"))
            .child(Element::new("bsdf").child(Element::new("float").attr("value", "0.5")));
        let mut s = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<!-- hi -->\n");
        e.write(&mut s, 0);
        assert_eq!(parse(&s).unwrap(), e);
    }

    #[test]
    fn malformed_documents_are_refused() {
        for bad in [
            "",
            "<a>",
            "<a></b>",
            "<a x=1/>",
            "<a x=\"1\" x=\"2\"/>",
            "<a/><b/>",
            "<a>text</a>",
            "<a><!-- x -- y --></a>",
            "<a x=\"&bogus;\"/>",
            "<!DOCTYPE a><a/>",
            "<a x=\"1\"y=\"2\"/>",
        ] {
            assert!(parse(bad).is_err(), "accepted {bad:?}");
        }
        assert!(parse("<a x='1'>\n <b/> <!-- c --> </a>\n").is_ok());
    }

    #[test]
    fn comments_never_contain_double_dashes() {
        for s in ["a--b", "a---b", "ends-", "----"] {
            let c = comment_text(s);
            assert!(!c.contains("--") && !c.ends_with('-'), "{c:?}");
            assert!(parse(&format!("<!--{c}--><a/>")).is_ok());
        }
    }
}
