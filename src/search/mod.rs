//! The candidate sweep (Peters & Klein 2015, Section 3.2, Fig. 4): every m-subset of the catalog
//! scored by Algorithm 1 over the depth stacks, with racing, shards and resumable results.
