//! Host-side tools for wraster: the f64 reference rasterizer, the standard scenes, a framebuffer target.
