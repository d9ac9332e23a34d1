//! Where a glTF model's bytes come from: its binary chunk, data URIs, and files beside it.
//! Everything the `gltf` crate would read or slice unchecked is checked here first: a URI's
//! percent-escapes must decode to UTF-8, a file must be a regular file within
//! [`MAX_SIDE_FILE_BYTES`] inside the model's folder (unless allowed), a buffer must hold the
//! bytes it declares, and an image's buffer view must lie inside its buffer.

use super::error::MeshError;
use crate::infra::limits::{MAX_SIDE_FILE_BYTES, read_regular_file};
use base64::Engine;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether URIs may name files outside the model's folder (`--allow-outside-uris`): a process-wide
/// choice of the user's, like the command line it comes from.
static ALLOW_OUTSIDE_URIS: AtomicBool = AtomicBool::new(false);

/// Lets glTF URIs name files outside their model's folder (off by default: a model from
/// elsewhere must not read `../../etc/passwd`).
pub fn set_allow_outside_uris(allow: bool) {
    ALLOW_OUTSIDE_URIS.store(allow, Ordering::Relaxed);
}

/// Reads a model's buffers and images.
pub(super) struct Sources<'a> {
    /// The model file.
    pub path: &'a Path,
    /// Its folder: relative URIs resolve against it.
    pub base: &'a Path,
}

impl Sources<'_> {
    fn invalid(&self, message: String) -> MeshError {
        MeshError::Invalid {
            path: self.path.to_owned(),
            message,
        }
    }

    /// Every buffer's bytes, padded to a multiple of four as the `gltf` crate's reader expects.
    pub(super) fn buffers(
        &self,
        document: &gltf::Document,
        mut blob: Option<Vec<u8>>,
    ) -> Result<Vec<gltf::buffer::Data>, MeshError> {
        let mut out = Vec::new();
        for buffer in document.buffers() {
            let what = format!("buffer {}", buffer.index());
            let mut data = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    self.invalid(format!("{what} is the binary chunk, which the file lacks"))
                })?,
                gltf::buffer::Source::Uri(uri) => self.uri_bytes(uri, &what)?,
            };
            if data.len() < buffer.length() {
                return Err(self.invalid(format!(
                    "{what} holds {} bytes, fewer than the {} it declares",
                    data.len(),
                    buffer.length()
                )));
            }
            while !data.len().is_multiple_of(4) {
                data.push(0);
            }
            out.push(gltf::buffer::Data(data));
        }
        Ok(out)
    }

    /// The encoded bytes of `image` (PNG, JPEG): a slice of a buffer, or a URI's.
    pub(super) fn image_bytes(
        &self,
        image: &gltf::Image,
        buffers: &[gltf::buffer::Data],
    ) -> Result<Vec<u8>, MeshError> {
        let what = format!("image {}", image.index());
        match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = buffers
                    .get(view.buffer().index())
                    .map_or(&[][..], |b| &b.0[..]);
                let end = view.offset().checked_add(view.length());
                match end.and_then(|end| buffer.get(view.offset()..end)) {
                    Some(bytes) => Ok(bytes.to_vec()),
                    None => Err(self.invalid(format!(
                        "{what}: its buffer view {} reaches past the end of buffer {} ({} bytes)",
                        view.index(),
                        view.buffer().index(),
                        buffer.len()
                    ))),
                }
            }
            gltf::image::Source::Uri { uri, .. } => self.uri_bytes(uri, &what),
        }
    }

    /// The bytes a URI names: a base64 data URI, or a file.
    fn uri_bytes(&self, uri: &str, what: &str) -> Result<Vec<u8>, MeshError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((_, data)) = rest.split_once(";base64,") else {
                return Err(self.invalid(format!(
                    "{what}: a data URI without base64 data is not supported"
                )));
            };
            return base64::engine::general_purpose::STANDARD
                .decode(data)
                .map_err(|e| self.invalid(format!("{what}: its data URI is not base64: {e}")));
        }
        let file = self.uri_path(uri, what)?;
        read_regular_file(&file, MAX_SIDE_FILE_BYTES)
            .map_err(|e| self.invalid(format!("{what}: cannot read {}: {e}", file.display())))
    }

    /// The file a URI names, refused when it leaves the model's folder (unless allowed).
    fn uri_path(&self, uri: &str, what: &str) -> Result<PathBuf, MeshError> {
        let (path, absolute) = match uri.split_once("://") {
            Some(("file", rest)) => (rest, true),
            Some((scheme, _)) => {
                return Err(self.invalid(format!(
                    "{what}: hprt reads files, not {scheme} URIs ({uri:?})"
                )));
            }
            None => (uri, false),
        };
        let decoded = percent_decode(path).ok_or_else(|| {
            self.invalid(format!(
                "{what}: the URI {uri:?} has percent-escapes that are not UTF-8 text"
            ))
        })?;
        let file = if absolute {
            PathBuf::from(&decoded)
        } else {
            self.base.join(&decoded)
        };
        if ALLOW_OUTSIDE_URIS.load(Ordering::Relaxed) {
            return Ok(file);
        }
        let inside = match (file.canonicalize(), self.base.canonicalize()) {
            (Ok(file), Ok(base)) => file.starts_with(base),
            // Not there: read_regular_file names the missing file.
            (Err(_), _) => !absolute && !Path::new(&decoded).components().any(is_up_or_root),
            (Ok(_), Err(_)) => false,
        };
        if !inside {
            return Err(self.invalid(format!(
                "{what}: the URI {uri:?} leads outside the model's folder; hprt reads only \
                 files beside the model unless given --allow-outside-uris"
            )));
        }
        Ok(file)
    }
}

fn is_up_or_root(c: std::path::Component) -> bool {
    !matches!(
        c,
        std::path::Component::Normal(_) | std::path::Component::CurDir
    )
}

/// `%XX` escapes decoded; `None` when they do not make UTF-8 text (or an escape is cut short).
fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
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
    fn percent_escapes_must_make_utf8() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("%C3%A9.png").as_deref(), Some("é.png"));
        assert_eq!(percent_decode("%FF%FE.bin"), None);
        assert_eq!(percent_decode("cut%2"), None);
    }

    #[test]
    fn uris_stay_in_the_models_folder() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("inner/model.gltf");
        std::fs::create_dir_all(model.parent().unwrap()).unwrap();
        std::fs::write(dir.path().join("secret.bin"), [1u8; 8]).unwrap();
        std::fs::write(dir.path().join("inner/ok.bin"), [2u8; 8]).unwrap();
        let sources = Sources {
            path: &model,
            base: model.parent().unwrap(),
        };
        assert_eq!(sources.uri_bytes("ok.bin", "buffer 0").unwrap(), [2u8; 8]);
        for uri in [
            "../secret.bin",
            "../../../../etc/passwd",
            "file:///dev/zero",
        ] {
            let e = sources.uri_bytes(uri, "buffer 0").unwrap_err().to_string();
            assert!(e.contains("outside the model's folder"), "{uri}: {e}");
        }
        let e = sources
            .uri_bytes("http://x/y.bin", "buffer 0")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not http URIs"), "{e}");
        assert_eq!(
            sources
                .uri_bytes("data:application/octet-stream;base64,AQID", "buffer 0")
                .unwrap(),
            [1, 2, 3]
        );
    }
}
