//! Sonar scanlines to obstacle features (placeholder).
