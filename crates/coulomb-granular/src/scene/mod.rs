//! Scenes: the model (`model`), its files (`file`, `save`), fills and particle files
//! (`generate`, `import`), URDF robots (`urdf`) and the built-in scenes (`builtin`, re-exported here).

pub mod builtin;
pub mod file;
pub mod generate;
pub mod import;
pub mod model;
pub mod save;
pub mod urdf;
mod urdf_reader;

pub use builtin::*;
