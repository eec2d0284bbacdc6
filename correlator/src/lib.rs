//! CORRELI-GD digital image correlation on a parallel mesh of zones of interest, and strains.
