//! Seeded synthetic office (placeholder).
