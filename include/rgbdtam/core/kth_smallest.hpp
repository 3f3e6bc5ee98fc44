#pragma once
// The k-th smallest of n floats, as std::nth_element finds it, in fewer operations: one pass
// counts the values by their top 11 bits (the sign, the exponent and two bits of mantissa), a
// second moves those of the bin that holds rank k to the front, and nth_element selects among
// them only (a few percent of the tracker's residuals). The tracker takes two medians per term
// and iteration (its MAD scales), where nth_element over every residual was a fifth of its time.

namespace rgbdtam {

// The value of rank k (0-based) of values[0, n), 0 <= k < n; values are finite. They are
// reordered, none lost or changed. Uses 8 kB of stack.
float kth_smallest(float* values, int n, int k);

}  // namespace rgbdtam
