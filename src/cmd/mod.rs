//! One module per subcommand. Each defines `Args` (its options, whose doc
//! comments are its `--help`) and `run(&Args)`; commands that others reuse
//! (the demo runs synth, fit, map, reconstruct and report) also expose the
//! work without the printing.

pub mod demo;
pub mod eval;
pub mod export;
pub mod fit;
pub mod info;
pub mod locate;
pub mod map;
pub mod nbrdf;
pub mod prepare;
pub mod reconstruct;
pub mod report;
pub mod swatches;
pub mod synth;
