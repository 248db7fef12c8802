//! Outputs: the statistics record (`report`), VTK frames (`output`), the output folder
//! (`output_dir`) and sphere checkpoints (`checkpoint`).

pub mod checkpoint;
pub mod output;
pub mod output_dir;
pub mod report;
