//! PLY and OBJ readers and writers (in progress).
