//! Rasterised pictures (PNG, GIF).
