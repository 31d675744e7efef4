// The five frost textures imagecorruptions draws from, embedded as their encoded files (frost.cpp
// decodes them), so the tool needs no data files at run time. FROST_DIR is set by
// lib/corruption/CMakeLists.txt.
#ifndef FROST_DIR
#error "FROST_DIR must name the frost_textures directory"
#endif

#define FAULTLINE_EMBED(sym, file)    \
  __asm__(                            \
      ".section .rodata\n"            \
      ".balign 16\n"                  \
      ".global " #sym "_begin\n" #sym \
      "_begin:\n"                     \
      ".incbin \"" FROST_DIR "/" file \
      "\"\n"                          \
      ".global " #sym "_end\n" #sym   \
      "_end:\n"                       \
      ".previous\n");

FAULTLINE_EMBED(faultline_frost1, "frost1.png")
FAULTLINE_EMBED(faultline_frost2, "frost2.png")
FAULTLINE_EMBED(faultline_frost3, "frost3.png")
FAULTLINE_EMBED(faultline_frost4, "frost4.jpg")
FAULTLINE_EMBED(faultline_frost5, "frost5.jpg")
