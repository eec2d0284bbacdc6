//! Simulated ASTREE multiaxial servo-hydraulic test machine (not implemented yet).
