//! Colour science: sRGB, CIE XYZ, CIELAB and the scaled space (spec section 1).
