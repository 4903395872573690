//! The commands, one module each, named as the command line spells them. Each takes its
//! validated configuration (see `config`) and reads top to bottom as the flow it runs.

pub mod bench;
pub mod compare;
pub mod render;
pub mod scenes;
pub mod techniques;
pub mod view;
