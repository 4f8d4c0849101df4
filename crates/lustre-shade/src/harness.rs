//! The quality harness (002 §8, 000 Fig. 4.24).
