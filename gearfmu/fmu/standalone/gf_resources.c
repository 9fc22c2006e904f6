/*
 * gf_resources.c -- what a model of the standalone runtime needs to read its resources
 * (gf_resources.h): the SHA-256 of a file (FIPS 180-4), resource files opened by their UTF-8 path
 * (UTF-16 with the long-path prefix on Windows), the key=value lines of a configuration file, the
 * variable table (var= lines, docs/standalone.md) and its FMI 3 arrays, the byte order of the
 * tables.  Used by the gear model (gear_model.c) and the gearbox model (gearbox_model.c); calls
 * nothing of the plumbing.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gf_resources.h"

/* ------------------------------------------------------------- SHA-256 */
/* FIPS 180-4 section 6.2 (SHA-256), written from the standard's text. */

static const uint32_t SHA_K[64] = {
    0x428a2f98u, 0x71374491u, 0xb5c0fbcfu, 0xe9b5dba5u, 0x3956c25bu, 0x59f111f1u, 0x923f82a4u, 0xab1c5ed5u,
    0xd807aa98u, 0x12835b01u, 0x243185beu, 0x550c7dc3u, 0x72be5d74u, 0x80deb1feu, 0x9bdc06a7u, 0xc19bf174u,
    0xe49b69c1u, 0xefbe4786u, 0x0fc19dc6u, 0x240ca1ccu, 0x2de92c6fu, 0x4a7484aau, 0x5cb0a9dcu, 0x76f988dau,
    0x983e5152u, 0xa831c66du, 0xb00327c8u, 0xbf597fc7u, 0xc6e00bf3u, 0xd5a79147u, 0x06ca6351u, 0x14292967u,
    0x27b70a85u, 0x2e1b2138u, 0x4d2c6dfcu, 0x53380d13u, 0x650a7354u, 0x766a0abbu, 0x81c2c92eu, 0x92722c85u,
    0xa2bfe8a1u, 0xa81a664bu, 0xc24b8b70u, 0xc76c51a3u, 0xd192e819u, 0xd6990624u, 0xf40e3585u, 0x106aa070u,
    0x19a4c116u, 0x1e376c08u, 0x2748774cu, 0x34b0bcb5u, 0x391c0cb3u, 0x4ed8aa4au, 0x5b9cca4fu, 0x682e6ff3u,
    0x748f82eeu, 0x78a5636fu, 0x84c87814u, 0x8cc70208u, 0x90befffau, 0xa4506cebu, 0xbef9a3f7u, 0xc67178f2u};

#define ROTR(x, n) (((x) >> (n)) | ((x) << (32 - (n))))

static void sha_block(gf_sha256 *s, const unsigned char *p)
{
    uint32_t w[64], a, b, c, d, e, f, g, h, t1, t2;
    int i;
    for (i = 0; i < 16; ++i)
        w[i] = ((uint32_t)p[4 * i] << 24) | ((uint32_t)p[4 * i + 1] << 16) | ((uint32_t)p[4 * i + 2] << 8) |
               (uint32_t)p[4 * i + 3];
    for (i = 16; i < 64; ++i) {
        uint32_t s0 = ROTR(w[i - 15], 7) ^ ROTR(w[i - 15], 18) ^ (w[i - 15] >> 3);
        uint32_t s1 = ROTR(w[i - 2], 17) ^ ROTR(w[i - 2], 19) ^ (w[i - 2] >> 10);
        w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    a = s->h[0]; b = s->h[1]; c = s->h[2]; d = s->h[3];
    e = s->h[4]; f = s->h[5]; g = s->h[6]; h = s->h[7];
    for (i = 0; i < 64; ++i) {
        t1 = h + (ROTR(e, 6) ^ ROTR(e, 11) ^ ROTR(e, 25)) + ((e & f) ^ (~e & g)) + SHA_K[i] + w[i];
        t2 = (ROTR(a, 2) ^ ROTR(a, 13) ^ ROTR(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
        h = g; g = f; f = e; e = d + t1;
        d = c; c = b; b = a; a = t1 + t2;
    }
    s->h[0] += a; s->h[1] += b; s->h[2] += c; s->h[3] += d;
    s->h[4] += e; s->h[5] += f; s->h[6] += g; s->h[7] += h;
}

void gfr_sha_init(gf_sha256 *s)
{
    static const uint32_t H0[8] = {0x6a09e667u, 0xbb67ae85u, 0x3c6ef372u, 0xa54ff53au,
                                   0x510e527fu, 0x9b05688cu, 0x1f83d9abu, 0x5be0cd19u};
    memcpy(s->h, H0, sizeof H0);
    s->len = 0;
    s->nbuf = 0;
}

void gfr_sha_update(gf_sha256 *s, const unsigned char *p, size_t n)
{
    s->len += (uint64_t)n;
    while (n > 0) {
        size_t take = 64 - s->nbuf;
        if (take > n) take = n;
        memcpy(s->buf + s->nbuf, p, take);
        s->nbuf += take;
        p += take;
        n -= take;
        if (s->nbuf == 64) {
            sha_block(s, s->buf);
            s->nbuf = 0;
        }
    }
}

void gfr_sha_final_hex(gf_sha256 *s, char hex[65])
{
    uint64_t bits = s->len * 8u;
    unsigned char pad = 0x80, zero = 0, lenb[8];
    int i;
    gfr_sha_update(s, &pad, 1);
    while (s->nbuf != 56) gfr_sha_update(s, &zero, 1);
    for (i = 0; i < 8; ++i) lenb[i] = (unsigned char)(bits >> (56 - 8 * i));
    gfr_sha_update(s, lenb, 8);
    for (i = 0; i < 8; ++i) sprintf(hex + 8 * i, "%08x", (unsigned)s->h[i]);
    hex[64] = '\0';
}

/* ----------------------------------------------------------- utilities */
void gfr_copy_str(char *dst, size_t cap, const char *src)
{
    size_t n = strlen(src);
    if (n >= cap) n = cap - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

/* folder (ending in a separator, else one is added) + fname */
int gfr_join_path(const char *dir, const char *fname, char *out, size_t cap)
{
    size_t n = strlen(dir);
    int sep = n > 0 && dir[n - 1] != '/' && dir[n - 1] != '\\';
    if (n + (size_t)sep + strlen(fname) + 1 > cap) return 0;
    memcpy(out, dir, n);
    if (sep) out[n++] = '/';
    memcpy(out + n, fname, strlen(fname) + 1);
    return 1;
}

/* Open a resource file for reading by its UTF-8 path (FMI strings are UTF-8: the decoded
 * resource URI of FMI 2, the resource path of FMI 3).  POSIX systems take the bytes as they are.
 * Windows reads a char path in the ANSI code page, so there the path is decoded from UTF-8 into
 * UTF-16 and opened with _wfopen.  A path of 250 characters or more (MAX_PATH is 260 with the
 * terminating zero) is given the long-path prefix "\\?\" (X:\dir -> \\?\X:\dir, and
 * \\server\share -> \\?\UNC\server\share), which lifts that limit; the prefix needs a path
 * without "." or ".." parts, so such a path is opened without it. */
#ifdef _WIN32
#include <wchar.h>

/* UTF-8 -> UTF-16 (RFC 3629, RFC 2781): the number of UTF-16 units written to out (cap units,
 * out may be NULL to count), -1 if s is not valid UTF-8 */
static long utf8_to_utf16(const char *s, wchar_t *out, size_t cap)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t n = 0;
    while (*p != 0) {
        unsigned long cp;
        int extra, k;
        if (*p < 0x80) { cp = *p; extra = 0; }
        else if ((*p & 0xE0) == 0xC0) { cp = *p & 0x1Fu; extra = 1; }
        else if ((*p & 0xF0) == 0xE0) { cp = *p & 0x0Fu; extra = 2; }
        else if ((*p & 0xF8) == 0xF0) { cp = *p & 0x07u; extra = 3; }
        else return -1;
        for (k = 1; k <= extra; ++k) {
            if ((p[k] & 0xC0) != 0x80) return -1;
            cp = (cp << 6) | (p[k] & 0x3Fu);
        }
        if ((extra == 1 && cp < 0x80) || (extra == 2 && cp < 0x800) || (extra == 3 && cp < 0x10000) ||
            cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
            return -1; /* overlong, beyond Unicode or a surrogate */
        p += extra + 1;
        if (cp >= 0x10000) {
            if (out != NULL && n + 2 <= cap) {
                out[n] = (wchar_t)(0xD800 + ((cp - 0x10000) >> 10));
                out[n + 1] = (wchar_t)(0xDC00 + ((cp - 0x10000) & 0x3FF));
            }
            n += 2;
        } else {
            if (out != NULL && n + 1 <= cap) out[n] = (wchar_t)cp;
            n += 1;
        }
    }
    return (long)n;
}

static FILE *open_read(const char *path)
{
    long n = utf8_to_utf16(path, NULL, 0);
    wchar_t *w, *start;
    FILE *f;
    long i;
    if (n < 0) return NULL;
    w = (wchar_t *)malloc(sizeof(wchar_t) * ((size_t)n + 9));
    if (w == NULL) return NULL;
    start = w + 8; /* the path; a prefix goes in front of it */
    utf8_to_utf16(path, start, (size_t)n);
    start[n] = 0;
    for (i = 0; i < n; ++i)
        if (start[i] == L'/') start[i] = L'\\';
    if (n >= 250 && wcsstr(start, L"\\.\\") == NULL && wcsstr(start, L"\\..\\") == NULL) {
        if (((start[0] >= L'A' && start[0] <= L'Z') || (start[0] >= L'a' && start[0] <= L'z')) && start[1] == L':' &&
            start[2] == L'\\') {
            start -= 4; /* X:\... -> \\?\X:\... */
            memcpy(start, L"\\\\?\\", 4 * sizeof(wchar_t));
        } else if (start[0] == L'\\' && start[1] == L'\\' && start[2] != L'?' && start[2] != L'.') {
            start -= 6; /* \\server\share -> \\?\UNC\server\share: "\\?\UNC" replaces the first '\' */
            memcpy(start, L"\\\\?\\UNC", 7 * sizeof(wchar_t));
        }
    }
    f = _wfopen(start, L"rb");
    free(w);
    return f;
}
#else
static FILE *open_read(const char *path) { return fopen(path, "rb"); }
#endif

unsigned char *gfr_read_file(const char *path, size_t *size)
{
    FILE *f = open_read(path);
    unsigned char *buf;
    long len;
    if (f == NULL) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return NULL;
    }
    buf = (unsigned char *)malloc((size_t)len + 1);
    if (buf == NULL) {
        fclose(f);
        return NULL;
    }
    if (len > 0 && fread(buf, 1, (size_t)len, f) != (size_t)len) {
        free(buf);
        fclose(f);
        return NULL;
    }
    fclose(f);
    buf[len] = 0;
    *size = (size_t)len;
    return buf;
}

int gfr_parse_double(const char *s, double *v)
{
    char *end;
    if (s == NULL || *s == '\0') return 0;
    *v = strtod(s, &end);
    return *end == '\0';
}

int gfr_parse_long(const char *s, long *v)
{
    char *end;
    if (s == NULL || *s == '\0') return 0;
    *v = strtol(s, &end, 10);
    return *end == '\0';
}

unsigned char *gfr_read_resource(const char *res_dir, const char *name, size_t *size, char *err, size_t errcap)
{
    char path[4096];
    unsigned char *text;
    if (!gfr_join_path(res_dir, name, path, sizeof path)) {
        snprintf(err, errcap, "resource location too long");
        return NULL;
    }
    text = gfr_read_file(path, size);
    if (text == NULL) snprintf(err, errcap, "cannot read resources/%s (path %.500s)", name, path);
    return text;
}

int gfr_next_config_line(const char **p, char *line, size_t cap, int *lineno, char **key, char **val, char *err,
                         size_t errcap)
{
    while (**p != '\0') {
        size_t n = strcspn(*p, "\n");
        char *eq;
        (*lineno)++;
        if (n >= cap) {
            snprintf(err, errcap, "line %d too long", *lineno);
            return -1;
        }
        memcpy(line, *p, n);
        line[n] = '\0';
        if (n > 0 && line[n - 1] == '\r') line[n - 1] = '\0';
        *p += n;
        if (**p == '\n') (*p)++;
        if (line[0] == '\0' || line[0] == '#') continue;
        eq = strchr(line, '=');
        if (eq == NULL) {
            snprintf(err, errcap, "line %d: no '='", *lineno);
            return -1;
        }
        *eq = '\0';
        *key = line;
        *val = eq + 1;
        return 1;
    }
    return 0;
}

/* split s at '|' into at most nmax fields (in place) */
int gfr_split_fields(char *s, char **fields, int nmax)
{
    int n = 0;
    fields[n++] = s;
    while (*s != '\0') {
        if (*s == '|') {
            *s = '\0';
            if (n == nmax) return -1;
            fields[n++] = s + 1;
        }
        s++;
    }
    return n;
}

int gfr_parse_var(gf_inst *c, char *val, int *count)
{
    char *f[9];
    long vr, oi;
    gf_var *v;
    if (gfr_split_fields(val, f, 9) != 9) return 0;
    if (!gfr_parse_long(f[0], &vr) || vr != *count || vr >= c->n_vars) return 0;
    v = &c->vars[vr];
    if (strcmp(f[1], "parameter") == 0) v->causality = GF_PARAMETER;
    else if (strcmp(f[1], "input") == 0) v->causality = GF_INPUT;
    else if (strcmp(f[1], "output") == 0) v->causality = GF_OUTPUT;
    else v->causality = GF_OTHER;
    if (strcmp(f[2], "fixed") == 0) v->variability = GF_FIXED;
    else if (strcmp(f[2], "tunable") == 0) v->variability = GF_TUNABLE;
    else if (strcmp(f[2], "continuous") == 0) v->variability = GF_CONTINUOUS;
    else v->variability = GF_OTHER_VAR;
    if (strcmp(f[3], "Integer") == 0) v->is_integer = 1;
    else if (strcmp(f[3], "Real") == 0) v->is_integer = 0;
    else return 0;
    if (f[4][0] == '\0') v->out_index = -1;
    else if (!gfr_parse_long(f[4], &oi)) return 0;
    else v->out_index = (int)oi;
    v->has_start = gfr_parse_double(f[5], &v->start);
    v->has_min = gfr_parse_double(f[6], &v->min);
    v->has_max = gfr_parse_double(f[7], &v->max);
    if ((f[5][0] && !v->has_start) || (f[6][0] && !v->has_min) || (f[7][0] && !v->has_max)) return 0;
    gfr_copy_str(v->name, sizeof v->name, f[8]);
    (*count)++;
    return 1;
}

int gfr_find_var(const gf_inst *c, const char *name)
{
    int i;
    for (i = 0; i < c->n_vars; ++i)
        if (strcmp(c->vars[i].name, name) == 0) return i;
    return -1;
}

int gfr_host_little_endian(void)
{
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

void gfr_swap8(unsigned char *p, size_t n_doubles)
{
    size_t i;
    int k;
    for (i = 0; i < n_doubles; ++i, p += 8)
        for (k = 0; k < 4; ++k) {
            unsigned char t = p[k];
            p[k] = p[7 - k];
            p[7 - k] = t;
        }
}

/* name[1], name[2], ... name[n] in a row: element 1 carries n (FMI 3 arrays, docs/fmu.md) */
void gfr_mark_arrays(gf_inst *c)
{
    int i = 0;
    while (i < c->n_vars) {
        const char *nm = c->vars[i].name;
        size_t len = strlen(nm);
        int n = 1;
        c->vars[i].array_len = 1;
        if (len > 3 && strcmp(nm + len - 3, "[1]") == 0) {
            char want[GF_MAX_NAME + 16];
            size_t base = len - 3;
            for (;;) {
                if (i + n >= c->n_vars) break;
                snprintf(want, sizeof want, "%.*s[%d]", (int)base, nm, n + 1);
                if (strcmp(c->vars[i + n].name, want) != 0) break;
                c->vars[i + n].array_len = 0;
                n++;
            }
            c->vars[i].array_len = n;
        }
        i += n;
    }
}
