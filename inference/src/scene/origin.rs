//! Where a scene's text came from, as messages name it.

use std::fmt;
use std::path::PathBuf;

/// A built-in scene (its text is in the binary, [`super::SHIPPED`]) or a
/// scene file read from disk. Messages name a built-in by its name: no file
/// of it need exist where the engine runs. (`Scene::source` keeps the
/// repository path a built-in was made from, for its relative mesh paths.)
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The built-in scene of this name.
    BuiltIn(String),
    /// The scene file at this path.
    File(PathBuf),
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::BuiltIn(name) => write!(f, "built-in scene '{name}'"),
            Origin::File(path) => write!(f, "{}", path.display()),
        }
    }
}
