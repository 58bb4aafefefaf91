//! A glTF file's buffers as bytes: the GLB's binary chunk, base64 `data:` URIs,
//! or files named by URIs relative to the glTF file (percent-encoded).

use std::path::Path;

use base64::Engine as _;
use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
use gltf::buffer::Source;

use crate::scene::error::SceneError;

/// Every buffer of `gltf` (read from `path`), each at least its declared
/// `byteLength` long.
pub(super) fn load(path: &Path, gltf: &mut gltf::Gltf) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut blob = gltf.blob.take();
    let mut buffers = Vec::new();
    for buffer in gltf.document.buffers() {
        let at = format!("buffer {}", buffer.index());
        let data = match buffer.source() {
            // Only the first buffer may use the binary chunk (glTF 2.0, 4.4.3.3).
            Source::Bin => blob.take().ok_or_else(|| {
                SceneError::gltf(
                    path,
                    &at,
                    "has no uri, but the file has no unused binary chunk \
                     (expected a .glb whose first buffer is its BIN chunk, or a uri)",
                )
            })?,
            Source::Uri(uri) => from_uri(path, &at, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(SceneError::gltf(
                path,
                at,
                format!(
                    "holds {} bytes (expected its byteLength, {})",
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The bytes a buffer's `uri` names: a base64 data URI, or a file relative to
/// the glTF file at `path`.
fn from_uri(path: &Path, at: &str, uri: &str) -> Result<Vec<u8>, SceneError> {
    let err = |message: String| SceneError::gltf(path, at, message);
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return Err(err(
                "data URI without a comma (expected data:…;base64,…)".into()
            ));
        };
        if !header.ends_with(";base64") {
            return Err(err(format!(
                "data URI `data:{header},…` is not base64 (expected data:…;base64,…)"
            )));
        }
        // Padding is optional in data URIs.
        let engine = GeneralPurpose::new(
            &base64::alphabet::STANDARD,
            GeneralPurposeConfig::new().with_decode_padding_mode(DecodePaddingMode::Indifferent),
        );
        return engine
            .decode(payload)
            .map_err(|e| err(format!("data URI: {e} (expected base64)")));
    }
    if let Some(scheme) = scheme_of(uri) {
        return Err(err(format!(
            "uri `{uri}`: unsupported scheme `{scheme}:` \
             (expected a data: URI or a path relative to the glTF file)"
        )));
    }
    let relative = percent_decode(uri).ok_or_else(|| {
        err(format!(
            "uri `{uri}` has a bad %-escape (expected %XX with hex digits, UTF-8)"
        ))
    })?;
    let file = path.parent().unwrap_or(Path::new(".")).join(relative);
    std::fs::read(&file).map_err(|e| {
        let cause = match e.kind() {
            std::io::ErrorKind::NotFound => {
                "not found (expected the buffer file, relative to the glTF file)".to_owned()
            }
            _ => e.to_string(),
        };
        err(format!("{}: {cause}", file.display()))
    })
}

/// The scheme of an absolute URI (`http` of `http://…`), or None for a
/// relative reference (RFC 3986: letters, digits, `+-.` before the first `:`,
/// which comes before any `/`).
fn scheme_of(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    let first_is_letter = chars.next().is_some_and(|c| c.is_ascii_alphabetic());
    let rest_ok = chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
    (first_is_letter && rest_ok).then_some(scheme)
}

/// `uri` with `%XX` escapes decoded; None when an escape is malformed or the
/// result is not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3)?;
            if !hex.iter().all(u8::is_ascii_hexdigit) {
                return None;
            }
            out.push(u8::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_and_schemes() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(
            percent_decode("plain/x.bin").as_deref(),
            Some("plain/x.bin")
        );
        assert_eq!(percent_decode("a%2"), None);
        assert_eq!(percent_decode("a%zz"), None);
        assert_eq!(percent_decode("a%+1"), None);
        assert_eq!(percent_decode("%ff"), None, "not UTF-8");
        assert_eq!(scheme_of("http://x/y.bin"), Some("http"));
        assert_eq!(scheme_of("file:///y.bin"), Some("file"));
        assert_eq!(scheme_of("y.bin"), None);
        assert_eq!(scheme_of("dir/a:b.bin"), None);
    }
}
