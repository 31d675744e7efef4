// Motion-blur kernel weights exactly as the reference computed them (NumPy SIMD exp, pairwise sum),
// from the golden kernels.json (spec corruptions.md §6). Tabulated because they cannot be
// recomputed portably.
#include "corruption/motion_kernel.hpp"

namespace faultline::corruption {
namespace {
constexpr double k_r10_s3[] = {
    0x1.e0c1f6d75df88p-3,  0x1.c6c6fb596e058p-3,  0x1.80f5ed2dbd8ffp-3,  0x1.239821f98cb1bp-3,
    0x1.8b4a704c85ce2p-4,  0x1.df830f2d8ad5fp-5,  0x1.0440ffcd7a4a0p-5,  0x1.f997877e4bdfap-7,
    0x1.b7756be6d4116p-8,  0x1.55ce9b86783e3p-9,  0x1.dbcb4b3f62f7dp-11, 0x1.2853e077f0c15p-12,
    0x1.4a4b317a47311p-14, 0x1.497018c973de6p-16, 0x1.2607b508995dap-18, 0x1.d5a96382f141ep-21,
    0x1.4fa7c194daec8p-23, 0x1.ad50dcdaa0735p-26, 0x1.eb5dcb02e8355p-29, 0x1.f73e93e834c0cp-32,
    0x1.cd3574db83ea0p-35,
};
constexpr double k_r10_s4[] = {
    0x1.7377e832c9ac6p-3,  0x1.680a1d11b2147p-3,  0x1.47d1d7e8ee6b6p-3,  0x1.186628178f7c4p-3,
    0x1.c29d2a9c5004fp-4,  0x1.54242858fe0fep-4,  0x1.e2647bc073b4bp-5,  0x1.4157ba920173fp-5,
    0x1.922ea6efb166ap-6,  0x1.d8dc89ce4fdf7p-7,  0x1.05238f95a2d1ap-7,  0x1.0ef4440afb866p-8,
    0x1.081ae2f340b62p-9,  0x1.e3aa13efe1058p-11, 0x1.a00afbc16db1dp-12, 0x1.50316c330cceap-13,
    0x1.fe6affd16c8e5p-15, 0x1.6bfd81be904f2p-16, 0x1.e7af94a4a0adbp-18, 0x1.32ea1188cc733p-19,
    0x1.6ae5125041a27p-21,
};
constexpr double k_r12_s4[] = {
    0x1.7377e213d30dfp-3,  0x1.680a1722f1526p-3,  0x1.47d1d282174cfp-3,  0x1.18662378c1269p-3,
    0x1.c29d232f7d6ccp-4,  0x1.542422be2d1d5p-4,  0x1.e26473cd93f12p-5,  0x1.4157b5467cc05p-5,
    0x1.922ea04f2b66bp-6,  0x1.d8dc8203a4849p-7,  0x1.05238b4813316p-7,  0x1.0ef43f9404915p-8,
    0x1.081ade992e069p-9,  0x1.e3aa0bf7a3cddp-11, 0x1.a00af4e66fc92p-12, 0x1.503166a8e3703p-13,
    0x1.fe6af7685490bp-15, 0x1.6bfd7bbf25322p-16, 0x1.e7af8c9b6cb6ep-18, 0x1.32ea0c7a24b2cp-19,
    0x1.6ae50c55757aep-21, 0x1.9316c1ea509e9p-23, 0x1.a49bab739f9bap-25, 0x1.9c4c3b12aadbbp-27,
    0x1.7baa5465b8818p-29,
};
constexpr double k_r12_s8[] = {
    0x1.85ec294269cbfp-4,  0x1.82e35ac1557bep-4, 0x1.79ed048670b83p-4, 0x1.6b729efac522ep-4,
    0x1.581afba903954p-4,  0x1.40bdd32993a6cp-4, 0x1.265435f241422p-4, 0x1.09e76f89822d3p-4,
    0x1.d8fff9f63f3d6p-5,  0x1.9e2c2cc289586p-5, 0x1.6509fffadf4fbp-5, 0x1.2f03deaccb03ep-5,
    0x1.fa5b724b6b968p-6,  0x1.a084a101ac086p-6, 0x1.514e7ec79ce38p-6, 0x1.0cec9dfd33eefp-6,
    0x1.a62984adcc1b2p-7,  0x1.4638bdfadb59fp-7, 0x1.f05a49a85d51cp-8, 0x1.73c040902aa29p-8,
    0x1.121cab31d9c22p-8,  0x1.8df7ca0be93b1p-9, 0x1.1c6a33b00c360p-9, 0x1.9038c018c6df0p-10,
    0x1.1539b77fb3e06p-10,
};
constexpr double k_r12_s12[] = {
    0x1.128208205e9bep-4, 0x1.118e72a482b9dp-4, 0x1.0eb8c00ef3972p-4, 0x1.0a0fed5590632p-4,
    0x1.03ac62c046f1ap-4, 0x1.f75e3ea7b6708p-5, 0x1.e4813b0ea640dp-5, 0x1.cf1efd10acf15p-5,
    0x1.b79e1762347eap-5, 0x1.9e6b3e8aac60ep-5, 0x1.83f60c097f591p-5, 0x1.68add546cfe1cp-5,
    0x1.4cfeb5acd79c6p-5, 0x1.314ee6fe535d2p-5, 0x1.15fc7d8a83b0ap-5, 0x1.f6b72f4ead297p-6,
    0x1.c36a1296cf40dp-6, 0x1.928b0c4c5a53bp-6, 0x1.647a8d1aa0437p-6, 0x1.39803ca620ec4p-6,
    0x1.11cbf0ad0605ep-6, 0x1.daee9a01e28b5p-7, 0x1.990fcfd42448dp-7, 0x1.5de39a0ab6848p-7,
    0x1.293472ab03184p-7,
};
constexpr double k_r15_s5[] = {
    0x1.2eaa1595e34afp-3,  0x1.28abd614bc3e5p-3,  0x1.1764fa84a3203p-3,  0x1.f99cf432aed66p-4,
    0x1.b78f14f33c392p-4,  0x1.6f2684f9b1f81p-4,  0x1.26a5289f0c542p-4,  0x1.c65f8b79ccec6p-5,
    0x1.509ba363015cbp-5,  0x1.df2cd45ad736bp-6,  0x1.47b07a8692669p-6,  0x1.ae9d50f1a868cp-7,
    0x1.0fd703cc23f1bp-7,  0x1.49c22b14062c5p-8,  0x1.8055147edf486p-9,  0x1.ae5fc53ac447cp-10,
    0x1.cf08e2be78930p-11, 0x1.dea3e527ee902p-12, 0x1.db5f13a58fe2dp-13, 0x1.c59cd441ec482p-14,
    0x1.9fe0a3b45bb15p-15, 0x1.6e54cb6c05506p-16, 0x1.3608f3e1ba976p-17, 0x1.f8340845a7175p-19,
    0x1.89e961d7bb21fp-20, 0x1.27adc7a9283b8p-21, 0x1.aa7b2d19bc699p-23, 0x1.278385187ef39p-24,
    0x1.8978d04bcf71ep-26, 0x1.f75bf66d96effp-28, 0x1.3557da8130e44p-29,
};
constexpr double k_r15_s8[] = {
    0x1.8529c6d72f2f6p-4,  0x1.82227b972f2a8p-4,  0x1.79309d228d398p-4,  0x1.6abd6f4e0f658p-4,
    0x1.576f707acd8fdp-4,  0x1.401dedb694641p-4,  0x1.25c17b4d46ac4p-4,  0x1.0962e0840e395p-4,
    0x1.d8142d18aee3cp-5,  0x1.9d5db38480588p-5,  0x1.645802305dfa9p-5,  0x1.2e6ccf7d89dd7p-5,
    0x1.f95f04538b898p-6,  0x1.9fb4fc6ce70c0p-6,  0x1.50a65744ba5aap-6,  0x1.0c668d8552ee3p-6,
    0x1.a5570fca5d33cp-7,  0x1.45961d25ba927p-7,  0x1.ef62d87ae8dffp-8,  0x1.7306ed37a17e9p-8,
    0x1.119404aa4ba17p-8,  0x1.8d3164dc426f2p-9,  0x1.1bdc6a4b1118fp-9,  0x1.8f713b4897ad3p-10,
    0x1.14af839fd563ep-10, 0x1.795dcabceb816p-11, 0x1.fab41ef8d91e9p-12, 0x1.4ee91ee177ac6p-12,
    0x1.b3dc6ab8a946ap-13, 0x1.1739193970632p-13, 0x1.603520a3357bfp-14,
};
constexpr double k_r15_s12[] = {
    0x1.0a6ba687d1e5ep-4, 0x1.097f3e31baf9ap-4, 0x1.06beeceeeecb0p-4, 0x1.02393eaa59dd5p-4,
    0x1.f80bc72cd433ep-5, 0x1.e889c3b6571b8p-5, 0x1.d63b0548a96e6p-5, 0x1.c17a0edf055cfp-5,
    0x1.aaaa6d8ea0744p-5, 0x1.9235a1ffda497p-5, 0x1.7887fbfe8db08p-5, 0x1.5e0d8940daa2ep-5,
    0x1.432f35d4ba485p-5, 0x1.2850387c896f7p-5, 0x1.0dcbdff7f3f38p-5, 0x1.e7e7a05b3e47bp-6,
    0x1.b61d6f9900abdp-6, 0x1.86af0162b22bcp-6, 0x1.59f9ef05e37ffp-6, 0x1.3043c3b87efd8p-6,
    0x1.09baec7165f68p-6, 0x1.ccf09741c89d4p-7, 0x1.8d029ad782607p-7, 0x1.5394af31b0b31p-7,
    0x1.2072e2042e01ep-7, 0x1.e6a3fb021a06cp-8, 0x1.97a9e45c48af5p-8, 0x1.5323fb9b41b12p-8,
    0x1.182ecf3bf6a0dp-8, 0x1.cbbed4f4bd53ap-9, 0x1.769518b39ac5ap-9,
};
constexpr double k_r20_s15[] = {
    0x1.ab5828bc1c1fcp-5,  0x1.aa65514ce3a1dp-5, 0x1.a79005c04e6bdp-5, 0x1.a2e1e40d637c8p-5,
    0x1.9c6ab70d67e26p-5,  0x1.94401dcdafd33p-5, 0x1.8a7d133f147acp-5, 0x1.7f4159eae0b9bp-5,
    0x1.72b0d0203a834p-5,  0x1.64f2b1ac665ffp-5, 0x1.5630cc9e723bep-5, 0x1.4696aed0d4903p-5,
    0x1.3650d1f8b040fp-5,  0x1.258bcbcc581b4p-5, 0x1.147387752a8bep-5, 0x1.03328cf99f12ep-5,
    0x1.e3e2b5453b241p-6,  0x1.c1aba7369c6b8p-6, 0x1.a0058c6b0be65p-6, 0x1.7f2f16c007166p-6,
    0x1.5f5f7fffb67c4p-6,  0x1.40c630181cf58p-6, 0x1.238a95117bd9ep-6, 0x1.07cc29a982279p-6,
    0x1.db454cb575d58p-7,  0x1.aa3caf6dc9781p-7, 0x1.7c9128b4faddbp-7, 0x1.524898bfe0912p-7,
    0x1.2b5d582db2f64p-7,  0x1.07bf97b582959p-7, 0x1.cead9cb6dfd6ap-8, 0x1.940656b8a31d0p-8,
    0x1.5f3e044c208c3p-8,  0x1.300050134a638p-8, 0x1.05f2798dc679bp-8, 0x1.c16b6242b3c93p-9,
    0x1.7fd26e891e9acp-9,  0x1.4658739ae6e1fp-9, 0x1.143ed9fa9ff2ap-9, 0x1.d19980be04743p-10,
    0x1.86a240272da74p-10,
};
}  // namespace

const TabulatedKernel* find_tabulated_kernel(int radius, int sigma) {
  static constexpr TabulatedKernel kTables[] = {
      {10, 3, k_r10_s3, 21}, {10, 4, k_r10_s4, 21},   {12, 4, k_r12_s4, 25},
      {12, 8, k_r12_s8, 25}, {12, 12, k_r12_s12, 25}, {15, 5, k_r15_s5, 31},
      {15, 8, k_r15_s8, 31}, {15, 12, k_r15_s12, 31}, {20, 15, k_r20_s15, 41},
  };
  for (const auto& t : kTables) {
    if (t.radius == radius && t.sigma == sigma) return &t;
  }
  return nullptr;
}

}  // namespace faultline::corruption
