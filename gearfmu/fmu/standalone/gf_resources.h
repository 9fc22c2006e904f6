/*
 * gf_resources.h -- reading a model's resources in the standalone runtime (gf_resources.c): the
 * SHA-256 of a file, resource files by their UTF-8 path, the fields of a configuration line, the
 * variable table of gf_model.h (var=vr|causality|variability|type|output_index|start|min|max|name
 * lines, docs/standalone.md) and its FMI 3 arrays.  Shared by the gear and the gearbox model.
 */
#ifndef GF_RESOURCES_H
#define GF_RESOURCES_H

#include <stddef.h>
#include <stdint.h>

#include "gf_model.h"

/* SHA-256 (FIPS 180-4 section 6.2): init, feed bytes, the 64 hex digits of the digest */
typedef struct {
    uint32_t h[8];
    uint64_t len;
    unsigned char buf[64];
    size_t nbuf;
} gf_sha256;

GF_API void gfr_sha_init(gf_sha256 *s);
GF_API void gfr_sha_update(gf_sha256 *s, const unsigned char *p, size_t n);
GF_API void gfr_sha_final_hex(gf_sha256 *s, char hex[65]);

/* src into dst[cap] (cut to fit, always terminated) */
GF_API void gfr_copy_str(char *dst, size_t cap, const char *src);
/* folder dir (a separator added when missing) + fname into out[cap]; 0 if it does not fit */
GF_API int gfr_join_path(const char *dir, const char *fname, char *out, size_t cap);
/* the whole file at the UTF-8 path (malloc'd, NUL after the last byte; *size its length), NULL if
 * it cannot be read */
GF_API unsigned char *gfr_read_file(const char *path, size_t *size);
/* the whole file resources/<name> under res_dir (as gfr_read_file); NULL with the reason in err (a
 * location too long, a file that cannot be read, naming it) */
GF_API unsigned char *gfr_read_resource(const char *res_dir, const char *name, size_t *size, char *err, size_t errcap);
/* the whole string s as a number (C99 hexadecimal floats read exactly); 1 on success */
GF_API int gfr_parse_double(const char *s, double *v);
GF_API int gfr_parse_long(const char *s, long *v);
/* The next key=value line of a configuration text at *p (the line copied into line[cap], its CR
 * dropped; blank and '#' lines skipped; *lineno counts every line): 1 with *key and *val pointing into
 * line, 0 at the end of the text, -1 with the reason in err (a line too long, a line without '='). */
GF_API int gfr_next_config_line(const char **p, char *line, size_t cap, int *lineno, char **key, char **val, char *err,
                                size_t errcap);
/* split s at '|' into at most nmax fields (in place); their number, -1 for more */
GF_API int gfr_split_fields(char *s, char **fields, int nmax);
/* one var= line's value into c->vars[*count] (value references in order from 0); 1 on success */
GF_API int gfr_parse_var(gf_inst *c, char *val, int *count);
/* the value reference of the variable called name, -1 if none */
GF_API int gfr_find_var(const gf_inst *c, const char *name);
/* the tables are stored little-endian (docs/tables.md): swap them on a big-endian host */
GF_API int gfr_host_little_endian(void);
GF_API void gfr_swap8(unsigned char *p, size_t n_doubles);
/* name[1], name[2], ... name[n] in a row: element 1 carries n (FMI 3 arrays, docs/fmu.md) */
GF_API void gfr_mark_arrays(gf_inst *c);

#endif /* GF_RESOURCES_H */
