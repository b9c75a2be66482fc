// Workgroup size of the screen-space compute passes.
const TILE: u32 = 8u;
