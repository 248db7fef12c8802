//! Outputs: the statistics record (`report`), VTK frames (`output`), the output folder
//! (`output_dir`) and checkpoints (`checkpoint`: the container, its reader and the sphere
//! layout; `rigid_checkpoint`: the layout of scenes with bodies of other shapes).

pub mod checkpoint;
pub mod output;
pub mod output_dir;
pub mod report;
pub mod rigid_checkpoint;
