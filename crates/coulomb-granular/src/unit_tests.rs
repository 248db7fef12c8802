//! The crate's unit tests, re-exported for its integration test binary
//! (`tests/unit.rs`). Written by `scripts/unit_tests.py`; do not edit.

pub mod bodies {
    pub mod dynamics {
        pub use crate::bodies::dynamics::tests;
    }
    pub mod joints {
        pub use crate::bodies::joints::tests;
    }
    pub mod mesh {
        pub use crate::bodies::mesh::tests;
    }
    pub mod shape {
        pub use crate::bodies::shape::tests;
    }
    pub mod world {
        pub use crate::bodies::world::tests;
    }
}
pub mod collision {
    pub mod contact {
        pub use crate::collision::contact::tests;
    }
    pub mod manifold {
        pub use crate::collision::manifold::tests;
    }
    pub mod tunnelling {
        pub use crate::collision::tunnelling::tests;
    }
}
#[cfg(feature = "mpi")]
pub mod distributed {
    pub mod grid {
        pub use crate::distributed::grid::tests;
    }
    pub mod slab {
        pub use crate::distributed::slab::tests;
    }
    pub mod subdomain {
        pub use crate::distributed::subdomain::tests;
    }
}
pub mod io {
    pub mod checkpoint {
        pub use crate::io::checkpoint::tests;
    }
    pub mod output {
        pub use crate::io::output::tests;
    }
    #[cfg(unix)]
    pub mod output_dir {
        pub use crate::io::output_dir::tests;
    }
    pub mod report {
        pub use crate::io::report::tests;
    }
    pub mod rigid_checkpoint {
        pub use crate::io::rigid_checkpoint::tests;
    }
}
pub mod math {
    pub use crate::math::tests;
}
pub mod run {
    pub use crate::run::tests;
}
pub mod scene {
    pub mod builtin {
        pub use crate::scene::builtin::tests;
    }
    pub mod file {
        pub use crate::scene::file::tests;
    }
    pub mod generate {
        pub use crate::scene::generate::tests;
    }
    pub mod import {
        pub use crate::scene::import::tests;
    }
    pub mod model {
        pub use crate::scene::model::tests;
    }
    pub mod rigid {
        pub use crate::scene::rigid::tests;
    }
    pub mod save {
        pub use crate::scene::save::tests;
    }
    pub mod urdf {
        pub use crate::scene::urdf::tests;
    }
    pub mod urdf_reader {
        pub use crate::scene::urdf_reader::tests;
    }
}
pub mod step {
    pub mod assembly {
        pub use crate::step::assembly::tests;
    }
    pub mod coarse {
        pub use crate::step::coarse::tests;
    }
    pub mod colour_progress {
        pub use crate::step::colour_progress::tests;
    }
    pub mod nsgs {
        pub use crate::step::nsgs::tests;
    }
    pub mod projection {
        pub use crate::step::projection::tests;
    }
    pub mod rigid {
        pub use crate::step::rigid::tests;
        pub mod correct {
            pub use crate::step::rigid::correct::tests;
        }
        pub mod equality {
            pub use crate::step::rigid::equality::tests;
        }
        pub mod nsgs {
            pub use crate::step::rigid::nsgs::tests;
        }
        pub mod relax {
            pub use crate::step::rigid::relax::tests;
        }
    }
    pub mod rolling {
        pub use crate::step::rolling::tests;
    }
    pub mod subspace {
        pub use crate::step::subspace::tests;
    }
}
pub mod validation {
    pub use crate::validation::tests;
    pub mod laws {
        pub use crate::validation::laws::tests;
    }
    pub mod rigid {
        pub use crate::validation::rigid::bench;
        pub use crate::validation::rigid::impact_tests;
        pub use crate::validation::rigid::report;
        pub use crate::validation::rigid::shape_tests;
        pub use crate::validation::rigid::stack_tests;
        pub use crate::validation::rigid::tests;
    }
}
