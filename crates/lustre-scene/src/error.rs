//! Errors of the scene readers: each names the file and the problem (with a line where the format
//! has lines); no input makes a reader panic.

use std::path::PathBuf;

/// Everything that can go wrong loading a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be opened or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A file that the scene refers to (a mesh, a texture, a map) does not exist.
    #[error("{}: referenced file {} does not exist", path.display(), referenced.display())]
    MissingFile {
        /// The scene file that refers to it.
        path: PathBuf,
        /// The missing file, resolved against the scene file's folder.
        referenced: PathBuf,
    },
    /// The file was read but its contents are not valid for its format.
    #[error("{}: {problem}", path.display())]
    Format {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// What is wrong, in words (with the line where there is one).
        problem: String,
    },
    /// A Mitsuba plugin (or element) that this reader does not know.
    #[error("{}: line {line}: unknown {kind} plugin {name:?}", path.display())]
    UnknownPlugin {
        /// The XML file.
        path: PathBuf,
        /// 1-based line of the element.
        line: u32,
        /// The element (`bsdf`, `shape`, `emitter`, `texture`, ...).
        kind: String,
        /// The plugin's `type`.
        name: String,
    },
    /// A glTF extension that the asset requires and this reader does not support.
    #[error("{}: required glTF extension {extension} is not supported", path.display())]
    UnsupportedExtension {
        /// The glTF file.
        path: PathBuf,
        /// The extension's name.
        extension: String,
    },
    /// Invalid geometry: non-finite vertices, indices out of range, mismatched attribute counts.
    #[error("{}: mesh {mesh:?}: {problem}", path.display())]
    Geometry {
        /// The file the mesh came from.
        path: PathBuf,
        /// The mesh's name.
        mesh: String,
        /// What is wrong.
        problem: String,
    },
    /// A material that cannot become a BSDF (bad parameters, an unresolvable spec).
    #[error("material {material:?}: {problem}")]
    Material {
        /// The material's name.
        material: String,
        /// What is wrong.
        problem: String,
    },
    /// An environment map that cannot be read.
    #[error(transparent)]
    Environment(#[from] lustre_env::EnvError),
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, SceneError>;

impl SceneError {
    /// A format error for `path`.
    pub fn format(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        SceneError::Format {
            path: path.into(),
            problem: problem.into(),
        }
    }

    /// A geometry error for mesh `mesh` of `path`.
    pub fn geometry(path: impl Into<PathBuf>, mesh: &str, problem: impl Into<String>) -> Self {
        SceneError::Geometry {
            path: path.into(),
            mesh: mesh.to_string(),
            problem: problem.into(),
        }
    }

    /// A material error.
    pub fn material(material: &str, problem: impl Into<String>) -> Self {
        SceneError::Material {
            material: material.to_string(),
            problem: problem.into(),
        }
    }
}

/// Reads a whole file; a missing file is [`SceneError::MissingFile`] naming `referrer`, any other
/// failure an [`SceneError::Io`].
pub(crate) fn read_referenced(
    referrer: &std::path::Path,
    path: &std::path::Path,
) -> Result<Vec<u8>> {
    lustre_brdf::error::read_input(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            SceneError::MissingFile {
                path: referrer.to_path_buf(),
                referenced: path.to_path_buf(),
            }
        } else {
            SceneError::Io {
                path: path.to_path_buf(),
                source: e,
            }
        }
    })
}
