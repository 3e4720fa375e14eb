//! The markup of the VTK XML files hvi reads back (`.vtu`/`.vtp`, `.pvtu`, `.pvd`), read by
//! quick-xml: tags, attributes with their entities resolved, the text between tags, nesting
//! checked. The bytes of raw appended data are not XML; [`parse_tags`] stops before them.

use quick_xml::errors::SyntaxError;
use quick_xml::escape::resolve_predefined_entity;
use quick_xml::events::{BytesStart, Event};
use quick_xml::{Reader, XmlVersion};

/// One tag: `<name a="v" ...>`, `<name .../>` or `</name>`, with the text that follows it up to
/// the next tag (entities resolved; empty for an end tag).
#[derive(Debug)]
pub(crate) struct Tag {
    pub(crate) name: String,
    attrs: Vec<(String, String)>,
    pub(crate) closing: bool,
    pub(crate) self_closing: bool,
    pub(crate) text: String,
}

impl Tag {
    /// The value of attribute `key`, entities resolved.
    pub(crate) fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }
}

/// The tags of `bytes` in order (the XML declaration, comments and processing instructions
/// skipped); with `stop_at`, parsing ends after the first start tag of that name, and the
/// second value is the position of the byte after its `>`. An error (one line: what, and at
/// which byte) for markup that is not well-formed: a bad tag or attribute, an unknown entity, an
/// end tag that closes no open element, or the end of the input inside an element.
pub(crate) fn parse_tags(bytes: &[u8], stop_at: Option<&str>) -> Result<(Vec<Tag>, Option<usize>), String> {
    let mut reader = Reader::from_reader(bytes);
    let mut tags: Vec<Tag> = Vec::new();
    let mut open: Vec<String> = Vec::new();
    let at = |reader: &Reader<&[u8]>| reader.buffer_position();
    let bad = |reader: &Reader<&[u8]>, e: &dyn std::fmt::Display| {
        format!("malformed XML at byte {}: {e}", reader.error_position())
    };
    loop {
        let event = reader.read_event().map_err(|e| match e {
            // every syntax error but one is markup that the end of the input cut
            quick_xml::Error::Syntax(s) if s != SyntaxError::InvalidBangMarkup => {
                bad(&reader, &format!("{s}; the file is truncated"))
            }
            e => bad(&reader, &e),
        })?;
        match event {
            Event::Start(e) => {
                let tag = start_tag(&reader, &e, false)?;
                open.push(tag.name.clone());
                let stop = stop_at == Some(tag.name.as_str());
                tags.push(tag);
                if stop {
                    let position = usize::try_from(at(&reader)).map_err(|e| bad(&reader, &e))?;
                    return Ok((tags, Some(position)));
                }
            }
            Event::Empty(e) => tags.push(start_tag(&reader, &e, true)?),
            Event::End(e) => {
                let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                open.pop();
                tags.push(Tag {
                    name,
                    attrs: Vec::new(),
                    closing: true,
                    self_closing: false,
                    text: String::new(),
                });
            }
            Event::Text(e) => {
                let text = e.decode().map_err(|e| bad(&reader, &e))?;
                push_text(&mut tags, &text);
            }
            Event::CData(e) => {
                let text = e.decode().map_err(|e| bad(&reader, &e))?;
                push_text(&mut tags, &text);
            }
            Event::GeneralRef(e) => {
                let name = e.decode().map_err(|e| bad(&reader, &e))?;
                let resolved = match e.resolve_char_ref().map_err(|e| bad(&reader, &e))? {
                    Some(c) => c.to_string(),
                    None => resolve_predefined_entity(&name)
                        .ok_or_else(|| bad(&reader, &format!("the unknown entity &{name};")))?
                        .to_string(),
                };
                push_text(&mut tags, &resolved);
            }
            Event::Decl(_) | Event::Comment(_) | Event::PI(_) | Event::DocType(_) => {}
            Event::Eof => {
                return match open.last() {
                    Some(name) => Err(format!("the file ends inside <{name}>; it is truncated")),
                    None => Ok((tags, None)),
                };
            }
        }
    }
}

/// Appends `text` to the text of the last tag (text before the first tag is dropped).
fn push_text(tags: &mut [Tag], text: &str) {
    if let Some(last) = tags.last_mut() {
        last.text.push_str(text);
    }
}

/// A start (or, `self_closing`, empty-element) tag with its attributes.
fn start_tag(reader: &Reader<&[u8]>, e: &BytesStart, self_closing: bool) -> Result<Tag, String> {
    let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    let bad = |what: &dyn std::fmt::Display| {
        format!(
            "malformed XML in the tag <{name}> ending at byte {}: {what}",
            reader.buffer_position()
        )
    };
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|e| bad(&e))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a
            .decoded_and_normalized_value(XmlVersion::Implicit1_0, reader.decoder())
            .map_err(|e| bad(&e))?
            .into_owned();
        attrs.push((key, value));
    }
    Ok(Tag {
        name,
        attrs,
        closing: false,
        self_closing,
        text: String::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_parse_with_escapes() {
        let (tags, rest) = parse_tags(
            b"<?xml version=\"1.0\"?>\n<!-- c > d --><R><A x=\"1\" y='a&amp;b &quot;q&quot; &lt;&gt;'/>t&amp;u</R>",
            None,
        )
        .unwrap();
        assert_eq!(rest, None);
        assert_eq!(tags.len(), 3);
        assert_eq!(
            (tags[1].name.as_str(), tags[1].self_closing, tags[1].closing),
            ("A", true, false)
        );
        assert_eq!(tags[1].attr("y"), Some("a&b \"q\" <>"));
        assert_eq!(tags[1].text, "t&u");
        assert!(tags[2].closing);
        let e = parse_tags(b"<A x=\"1>", None).unwrap_err();
        assert!(e.contains("truncated"), "{e}");
        assert!(parse_tags(b"<A x=1>", None).is_err());
        // an end tag that closes nothing, and an element left open
        assert!(parse_tags(b"<A/></A>", None).is_err());
        let e = parse_tags(b"<A><B/>", None).unwrap_err();
        assert!(e.contains("<A>") && e.contains("truncated"), "{e}");
    }

    #[test]
    fn parsing_stops_after_the_tag_asked_for() {
        let text = b"<V><D a=\"1\"/><App e=\"raw\">_\x00<\xff</App></V>";
        let (tags, rest) = parse_tags(text, Some("App")).unwrap();
        assert_eq!(tags.last().map(|t| t.name.as_str()), Some("App"));
        assert_eq!(&text[rest.unwrap()..rest.unwrap() + 1], b"_");
    }
}
