//! Offline side: scene, texgen, tracer, inference (placeholder).
