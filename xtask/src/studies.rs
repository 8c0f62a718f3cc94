//! Studies (placeholder).
