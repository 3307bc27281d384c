//! What a file that is not a MERL table looks like, so an error can say
//! "it looks like text" before the dims read from its characters.

/// What a file whose header is not a MERL header looks like, if its first
/// bytes say so: a known signature, or text (printable UTF-8 with only
/// tabs, line and page breaks among the control characters). A MERL header
/// never looks like text: text bytes make dims of 150 million and more.
pub fn looks_like(bytes: &[u8]) -> Option<&'static str> {
    const SIGNATURES: [(&[u8], &str); 6] = [
        (b"\x89PNG\r\n\x1a\n", "a PNG image"),
        (b"\x76\x2f\x31\x01", "an OpenEXR image"),
        (b"\xff\xd8\xff", "a JPEG image"),
        (b"\x1f\x8b", "a gzip-compressed file"),
        (b"PK\x03\x04", "a zip archive"),
        (b"\x7fELF", "a program"),
    ];
    if let Some((_, what)) = SIGNATURES.iter().find(|(sig, _)| bytes.starts_with(sig)) {
        return Some(what);
    }
    let head = &bytes[..bytes.len().min(1024)];
    let text = match std::str::from_utf8(head) {
        Ok(t) => t,
        // Cut inside a character at the end of the sample: still text.
        Err(e) if e.error_len().is_none() => std::str::from_utf8(&head[..e.valid_up_to()]).ok()?,
        Err(_) => return None,
    };
    let printable = |c: char| !c.is_control() || matches!(c, '\t' | '\n' | '\r' | '\x0c');
    (!text.is_empty() && text.chars().all(printable)).then_some("text")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_and_signatures_are_recognised_and_merl_headers_are_not() {
        assert_eq!(looks_like(b"measured 2024\r\n\tsee notes"), Some("text"));
        assert_eq!(looks_like("r\u{e9}sum\u{e9}".as_bytes()), Some("text"));
        // A sample cut inside a character is still text.
        let long = "\u{e9}".repeat(600);
        assert_eq!(looks_like(long.as_bytes()), Some("text"));
        assert_eq!(looks_like(b"\x89PNG\r\n\x1a\n\0"), Some("a PNG image"));
        assert_eq!(
            looks_like(b"\x1f\x8b\x08\0"),
            Some("a gzip-compressed file")
        );
        // Binary dims (with NUL bytes), an empty file: nothing to say.
        assert_eq!(looks_like(&[90, 0, 0, 0, 90, 0, 0, 0, 180, 0, 0, 0]), None);
        assert_eq!(looks_like(b""), None);
        assert_eq!(looks_like(b"text\0with a NUL"), None);
    }
}
