//! Reference (oracle) DEM: brute-force ellipse contact by dense boundary sampling, plain force laws.
