//! Contact detection of the sphere fast path: analytic sphere–sphere and sphere–obstacle
//! pairs on a grid broad phase (`contact`), and the tunnelling guard (`tunnelling`). Bodies of
//! other shapes are detected by parry3d in [`crate::rigid::contacts`].

pub mod contact;
pub mod tunnelling;
