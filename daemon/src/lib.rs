//! The emoshift library: CLI front ends and the service.
