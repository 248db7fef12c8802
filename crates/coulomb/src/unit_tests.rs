//! The crate's unit tests, re-exported for its integration test binary
//! (`tests/unit.rs`). Written by `scripts/unit_tests.py`; do not edit.

pub mod atomic {
    pub use crate::atomic::tests;
}
pub mod barrier {
    pub use crate::barrier::tests;
}
pub mod cone {
    pub use crate::cone::tests;
}
pub mod deadline {
    pub use crate::deadline::tests;
}
pub mod delassus {
    pub use crate::delassus::tests;
}
pub mod equality {
    pub use crate::equality::tests;
}
pub mod examples {
    pub use crate::examples::tests;
}
pub mod existence {
    pub use crate::existence::tests;
}
pub mod fclib {
    pub use crate::fclib::tests;
}
pub mod inner {
    pub mod apgd {
        pub use crate::inner::apgd::tests;
    }
    pub mod contact {
        pub use crate::inner::contact::tests;
    }
    pub mod faceted {
        pub use crate::inner::faceted::tests;
    }
    pub mod ipm {
        pub use crate::inner::ipm::tests;
    }
}
#[cfg(unix)]
pub mod input {
    pub use crate::input::tests;
}
pub mod law {
    pub use crate::law::tests;
}
pub mod levenberg {
    pub use crate::levenberg::tests;
}
pub mod linalg {
    pub mod dense {
        pub use crate::linalg::dense::tests;
    }
    pub mod skeleton {
        pub use crate::linalg::skeleton::tests;
    }
    pub mod sparse {
        pub use crate::linalg::sparse::tests;
    }
}
pub mod line_search {
    pub use crate::line_search::tests;
}
pub mod multiplier {
    pub use crate::multiplier::tests;
}
pub mod newton {
    pub use crate::newton::tests;
}
pub mod outer {
    pub use crate::outer::tests;
    pub mod anderson {
        pub use crate::outer::anderson::tests;
    }
    pub mod fixed_point {
        pub use crate::outer::fixed_point::tests;
    }
    pub mod fused {
        pub use crate::outer::fused::tests;
    }
}
pub mod plan {
    pub use crate::plan::tests;
}
pub mod problem {
    pub use crate::problem::tests;
}
pub mod proximal {
    pub use crate::proximal::tests;
}
pub mod settings {
    pub use crate::settings::tests;
}
pub mod solution {
    pub use crate::solution::tests;
}
