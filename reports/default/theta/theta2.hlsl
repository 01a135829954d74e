// Optimized moment quantization θ (momentlab theta; Peters & Klein 2015, Section 4.3).
// basis b = (z, z^2), m = 2
// stored s = A*b + t lies in [0,1]^2; entropy gain log2|det A| = 2.0000 bits.
// Encode before writing the shadow map; decode the filtered sample.
void EncodeMoments2(float z, out float s[2])
{
    float z1 = z;
    float z2 = z1 * z;
    float b[2];
    b[0] = z1;
    b[1] = z2;
    s[0] = 5.00000000000000031e-10 + 3.99999999600000011e0 * b[0] + -3.99999999600000011e0 * b[1];
    s[1] = 5.00000000000000031e-10 + 9.99999999000000028e-1 * b[0] + 0.00000000000000000e0 * b[1];
}

void DecodeMoments2(float s[2], out float b[2])
{
    float d[2];
    d[0] = s[0] - 5.00000000000000031e-10;
    d[1] = s[1] - 5.00000000000000031e-10;
    b[0] = 0.00000000000000000e0 * d[0] + 1.00000000100000008e0 * d[1];
    b[1] = -2.50000000250000021e-1 * d[0] + 1.00000000100000008e0 * d[1];
}
