/* kingen_hal.c: a stand-in for the few HAL and RTAPI functions a LinuxCNC kinematics module
 * imports, so that kingen can load a module (its own or LinuxCNC's stock ones) with dlopen
 * and call its kinematicsInverse and kinematicsForward on many poses, as LinuxCNC's motion
 * controller does, without LinuxCNC running. Pins and parameters are recorded by name, so
 * that they can be set (setp) and read back.
 *
 * Part of kingen (not generated). The types follow LinuxCNC 2.9's hal.h: float pins and
 * parameters are doubles, s32 and u32 are 32-bit integers, bits are one-byte booleans. */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KINGEN_HAL_MAX 512
#define KINGEN_HAL_NAME 96
#define KINGEN_HAL_NAME_LEN 47 /* hal.h's HAL_NAME_LEN: a longer name is refused, as by LinuxCNC's HAL */
#define KINGEN_HAL_FLOAT 0
#define KINGEN_HAL_S32 1
#define KINGEN_HAL_U32 2
#define KINGEN_HAL_BIT 3

typedef struct {
    char name[KINGEN_HAL_NAME];
    int type;
    void *address;
} kingen_hal_item;

typedef struct {
    double tran[3];
    double a, b, c, u, v, w;
} kingen_emc_pose;

typedef int (*kingen_inverse_t)(const kingen_emc_pose *, double *, const unsigned long *, unsigned long *);
typedef int (*kingen_forward_t)(const double *, kingen_emc_pose *, const unsigned long *, unsigned long *);

static kingen_hal_item kingen_items[KINGEN_HAL_MAX];
static int kingen_item_count;

static int kingen_record(const char *name, int type, void *address)
{
    if (kingen_item_count >= KINGEN_HAL_MAX || name == NULL || strlen(name) > KINGEN_HAL_NAME_LEN)
        return -1;
    strncpy(kingen_items[kingen_item_count].name, name, KINGEN_HAL_NAME - 1);
    kingen_items[kingen_item_count].name[KINGEN_HAL_NAME - 1] = '\0';
    kingen_items[kingen_item_count].type = type;
    kingen_items[kingen_item_count].address = address;
    kingen_item_count++;
    return 0;
}

/* A pin's value lives in memory of its own, kept as long as the process (a module holds it). */
static int kingen_pin(const char *name, int type, void **pointer)
{
    void *storage;
    if (kingen_item_count >= KINGEN_HAL_MAX || (storage = calloc(1, 8)) == NULL)
        return -1;
    *pointer = storage;
    return kingen_record(name, type, storage);
}

#define KINGEN_FORMAT(fmt, name) \
    char name[KINGEN_HAL_NAME]; \
    va_list arguments; \
    va_start(arguments, fmt); \
    vsnprintf(name, sizeof(name), fmt, arguments); \
    va_end(arguments)

int hal_init(const char *name) { (void)name; return 1; }
int hal_exit(int comp_id) { (void)comp_id; return 0; }
int hal_ready(int comp_id) { (void)comp_id; return 0; }
void *hal_malloc(long int size) { return calloc(1, (size_t)size); }

int hal_pin_float_new(const char *name, int dir, double **pointer, int comp_id)
{ (void)dir; (void)comp_id; return kingen_pin(name, KINGEN_HAL_FLOAT, (void **)pointer); }
int hal_pin_s32_new(const char *name, int dir, int32_t **pointer, int comp_id)
{ (void)dir; (void)comp_id; return kingen_pin(name, KINGEN_HAL_S32, (void **)pointer); }
int hal_pin_u32_new(const char *name, int dir, uint32_t **pointer, int comp_id)
{ (void)dir; (void)comp_id; return kingen_pin(name, KINGEN_HAL_U32, (void **)pointer); }
int hal_pin_bit_new(const char *name, int dir, unsigned char **pointer, int comp_id)
{ (void)dir; (void)comp_id; return kingen_pin(name, KINGEN_HAL_BIT, (void **)pointer); }

int hal_pin_float_newf(int dir, double **pointer, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_pin_float_new(name, dir, pointer, comp_id); }
int hal_pin_s32_newf(int dir, int32_t **pointer, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_pin_s32_new(name, dir, pointer, comp_id); }
int hal_pin_u32_newf(int dir, uint32_t **pointer, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_pin_u32_new(name, dir, pointer, comp_id); }
int hal_pin_bit_newf(int dir, unsigned char **pointer, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_pin_bit_new(name, dir, pointer, comp_id); }

int hal_param_float_new(const char *name, int dir, double *address, int comp_id)
{ (void)dir; (void)comp_id; return kingen_record(name, KINGEN_HAL_FLOAT, address); }
int hal_param_s32_new(const char *name, int dir, int32_t *address, int comp_id)
{ (void)dir; (void)comp_id; return kingen_record(name, KINGEN_HAL_S32, address); }
int hal_param_u32_new(const char *name, int dir, uint32_t *address, int comp_id)
{ (void)dir; (void)comp_id; return kingen_record(name, KINGEN_HAL_U32, address); }
int hal_param_bit_new(const char *name, int dir, unsigned char *address, int comp_id)
{ (void)dir; (void)comp_id; return kingen_record(name, KINGEN_HAL_BIT, address); }

int hal_param_float_newf(int dir, double *address, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_param_float_new(name, dir, address, comp_id); }
int hal_param_s32_newf(int dir, int32_t *address, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_param_s32_new(name, dir, address, comp_id); }
int hal_param_u32_newf(int dir, uint32_t *address, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_param_u32_new(name, dir, address, comp_id); }
int hal_param_bit_newf(int dir, unsigned char *address, int comp_id, const char *fmt, ...)
{ KINGEN_FORMAT(fmt, name); return hal_param_bit_new(name, dir, address, comp_id); }

void rtapi_print(const char *fmt, ...) { (void)fmt; }
void rtapi_print_msg(int level, const char *fmt, ...) { (void)level; (void)fmt; }

/* Forget the pins and parameters whose names start with prefix (before loading that module
 * again: a fresh copy makes them anew). */
void kingen_hal_forget(const char *prefix)
{
    int i, kept = 0;
    size_t length = strlen(prefix);
    for (i = 0; i < kingen_item_count; i++)
        if (strncmp(kingen_items[i].name, prefix, length) != 0)
            kingen_items[kept++] = kingen_items[i];
    kingen_item_count = kept;
}

static kingen_hal_item *kingen_find(const char *name)
{
    int i;
    for (i = 0; i < kingen_item_count; i++)
        if (strcmp(kingen_items[i].name, name) == 0)
            return &kingen_items[i];
    return NULL;
}

/* setp (write) or getp: 0 when the pin or parameter exists, -1 otherwise; *value is written
 * to it, converted to its type (a bit: value != 0), or read from it. */
static int kingen_access(const char *name, double *value, int write)
{
    kingen_hal_item *item = kingen_find(name);
    if (item == NULL)
        return -1;
    if (item->type == KINGEN_HAL_FLOAT) {
        if (write)
            *(double *)item->address = *value;
        else
            *value = *(double *)item->address;
    } else if (item->type == KINGEN_HAL_S32) {
        if (write)
            *(int32_t *)item->address = (int32_t)*value;
        else
            *value = *(int32_t *)item->address;
    } else if (item->type == KINGEN_HAL_U32) {
        if (write)
            *(uint32_t *)item->address = (uint32_t)*value;
        else
            *value = *(uint32_t *)item->address;
    } else if (write)
        *(unsigned char *)item->address = *value != 0.0;
    else
        *value = *(unsigned char *)item->address;
    return 0;
}

int kingen_hal_set(const char *name, double value) { return kingen_access(name, &value, 1); }
int kingen_hal_get(const char *name, double *value) { return kingen_access(name, value, 0); }
int kingen_hal_count(void) { return kingen_item_count; }
const char *kingen_hal_name(int index) { return index >= 0 && index < kingen_item_count ? kingen_items[index].name : NULL; }

/* kinematicsInverse (forward 0) over count poses (9 numbers each: x y z a b c u v w) into
 * joints (16 per pose), or kinematicsForward (forward 1) over count joint sets (16 each), each
 * started from poses[9 i ...] and overwritten with the result; the return values, and the pin
 * named pin after each call (when given; -1 when it cannot be read). */
void kingen_batch(void *routine, int forward, int count, double *poses, double *joints, int *returns,
                  const char *pin, double *pins)
{
    int i;
    for (i = 0; i < count; i++) {
        kingen_emc_pose world;
        unsigned long iflags = 0, fflags = 0;
        memcpy(&world, poses + 9 * i, sizeof(world));
        if (forward) {
            returns[i] = ((kingen_forward_t)routine)(joints + 16 * i, &world, &fflags, &iflags);
            memcpy(poses + 9 * i, &world, sizeof(world));
        } else
            returns[i] = ((kingen_inverse_t)routine)(&world, joints + 16 * i, &iflags, &fflags);
        if (pin != NULL && kingen_hal_get(pin, &pins[i]) != 0)
            pins[i] = -1.0;
    }
}
