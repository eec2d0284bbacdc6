//! Frame producer: simulated speckle camera and image-folder replay.
