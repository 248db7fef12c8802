//! Scenes: the model (`model`), its files (`file`, `save`), fills and particle files
//! (`generate`, `import`), URDF robots (`urdf`), the built-in scenes (`builtin`, re-exported
//! here) and a model with bodies of other shapes built into a stepped world (`rigid`).

pub mod builtin;
pub mod file;
pub mod generate;
pub mod import;
pub mod model;
pub mod rigid;
pub mod save;
pub mod urdf;
pub(crate) mod urdf_reader;

pub use builtin::*;
