//! Shared-memory layouts, service names and node construction for dicstream.
