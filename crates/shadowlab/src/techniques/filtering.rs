//! Filtering of map textures (being written).
