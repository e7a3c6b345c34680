//! Reading a frame file: text, parsed by serde into the [`super::schema`],
//! validated and built by [`super::build`] into a [`FrameFile`].

use std::path::Path;

use super::build::build;
use super::error::FrameFileError;
use super::file::FrameFile;
use super::schema::RawFile;

impl FrameFile {
    /// Reads, parses, validates and builds a frame file.
    ///
    /// # Errors
    /// The file cannot be read, is not of the format, or a value is invalid
    /// (the key is named).
    pub fn read(path: &Path) -> Result<FrameFile, FrameFileError> {
        let shown = path.display().to_string();
        let text = crate::input::read_input(path).map_err(|source| FrameFileError::Io {
            path: shown.clone(),
            source,
        })?;
        FrameFile::from_toml(&text).map_err(|e| match e {
            FrameFileError::Parse { source, .. } => FrameFileError::Parse {
                path: shown,
                source,
            },
            other => other,
        })
    }

    /// Parses, validates and builds frame-file text.
    ///
    /// # Errors
    /// As [`FrameFile::read`].
    pub fn from_toml(text: &str) -> Result<FrameFile, FrameFileError> {
        let raw: RawFile = toml::from_str(text).map_err(|source| FrameFileError::Parse {
            path: "<frame>".into(),
            source,
        })?;
        build(raw)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example of the module documentation, as written there.
    fn doc_example() -> String {
        let source = include_str!("mod.rs");
        let start = source
            .find("//! ```toml\n")
            .expect("the docs have an example");
        let end = start + source[start..].find("//! ```\n").expect("closed");
        source[start..end]
            .lines()
            .skip(1)
            .map(|l| l.strip_prefix("//!").unwrap_or(l).trim_start())
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn documented_example_builds() {
        let file = FrameFile::from_toml(&doc_example()).unwrap();
        assert_eq!(file.rods_labels, ["left", "beam", "right"]);
        assert_eq!(file.model.element_count(), 14);
        assert_eq!(file.model.node_count(), 5 + 7 + 5 + 2);
        assert_eq!(file.model.joint_count(), 4);
        assert_eq!(file.supported_nodes.len(), 2);
        assert_eq!(file.nodes_origins.len(), file.model.node_count());
        assert_eq!(file.body("knee-right"), Some(18));
    }

    #[test]
    fn ambiguous_node_member_lists_what_is_there() {
        let text = doc_example().replace("on = { node = \"a\" }", "on = { node = \"b\" }");
        let err = FrameFile::from_toml(&text).unwrap_err();
        assert_eq!(err.key(), Some("supports[0].on.node"));
        let message = err.to_string();
        assert!(
            message.contains("rod left end") && message.contains("body knee-left"),
            "{message}"
        );
    }
}
