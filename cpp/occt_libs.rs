// The Open CASCADE 7.6 libraries the STEP shim links, in link order (dependents
// first). One list for build.rs and for the tests that compile Open CASCADE
// checkers (`include!`d by both).
#[allow(dead_code)] // the default build (no `step`) links none of them
const OCCT_LIBS: [&str; 22] = [
    "TKXDESTEP",
    "TKSTEP",
    "TKSTEPBase",
    "TKSTEPAttr",
    "TKSTEP209",
    "TKXSBase",
    "TKXCAF",
    "TKLCAF",
    "TKCAF",
    "TKCDF",
    "TKMesh",
    "TKBO",
    "TKPrim",
    "TKTopAlgo",
    "TKShHealing",
    "TKGeomAlgo",
    "TKGeomBase",
    "TKBRep",
    "TKG3d",
    "TKG2d",
    "TKMath",
    "TKernel",
];
