// Where this compiler puts every field of record_fields.h: per entry its offset and size (a
// record's entry: 0 and the record's size), in the list's order. Offsets by address difference,
// which every OpenCL C compiler accepts (offsetof is not in OpenCL C 1.2).
#define LUCENT_PROBE_RECORD(T)    \
  {                               \
    out[i++] = 0;                 \
    out[i++] = (uint)sizeof(T);   \
  }
#define LUCENT_PROBE_FIELD(T, f)                                                          \
  {                                                                                       \
    T probe;                                                                              \
    out[i++] = (uint)((__private char*)&probe.f - (__private char*)&probe);               \
    out[i++] = (uint)sizeof(probe.f);                                                     \
  }

__kernel void recordLayout(__global uint* out) {
  uint i = 0;
  LUCENT_RECORD_FIELDS(LUCENT_PROBE_RECORD, LUCENT_PROBE_FIELD)
}
