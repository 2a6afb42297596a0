"""The compiled hot loop: forces on the airborne rope nodes, the interior-rope (nip) speed, and the
arbitrary Lagrangian-Eulerian transport of material through the guide eyelet.

Layout (all arrays preallocated to a capacity, ``n`` of them live):
    nodes 0 .. n-1 are material points in the air, ordered AGAINST the flow: node 0 is the next to
    re-enter the guide at the return point R, node n-1 the last to have left it at the exit point E.
    rest[k] (k < n-1) is the rest length of the segment between node k and node k+1; the two boundary
    segments R-node0 and node(n-1)-E have rest lengths rest_ret and rest_exit, which shrink / grow as
    rope is drawn in / paid out. When rest_exit >= 1.5 ds a node is born on the exit segment, when
    rest_ret < 0.5 ds node 0 is absorbed (and the converse when the rope runs backwards), so each
    material point flies from E round the loop to R, exactly as on the real ring.
    The rope inside the module (return point -> nip -> exit point) is one rigid 1-D body of mass
    lambda L_int moving at speed u; the nip drives it toward the wheel surface speed with a
    friction-limited grip.

Time stepping: semi-implicit (symplectic) Euler for the nodes, implicit in the stiff nip grip.
Forces per node: axial spring-dashpot tension (no compression beyond 1 % stiffness), discrete
bending (B/l (1 - cos theta) per vertex, ghost points inside the guide clamp the tangent there),
compression resisted only at a fraction (P_COMPRESSION) of EA, 
Kelvin-Voigt bending damping (internal friction of the yarn), gravity, quadratic tangential and normal air drag, penalty contact with friction.
"""

from __future__ import annotations

import numpy as np
from numba import njit


# obstacle rows (contact.py builds them): [kind, mu, geometry...]
OBSTACLE_ROW = 16
KIND_SPHERE, KIND_CAPSULE, KIND_BOX, KIND_HALFSPACE, KIND_CYLINDER = 0, 1, 2, 3, 4

# indices into the scalar parameter vector ``prm``
P_LAMBDA, P_EA, P_ETA, P_B, P_RHO, P_CF, P_CN, P_D = 0, 1, 2, 3, 4, 5, 6, 7
P_G, P_WX, P_WY, P_WZ, P_DS, P_GRIP, P_FMAX, P_KC = 8, 9, 10, 11, 12, 13, 14, 15
P_CC, P_RCONTACT, P_VREG, P_COMPRESSION, P_ETAB, P_DT = 16, 17, 18, 19, 20, 21
N_PRM = 22

# indices into the scalar state vector ``sc``
S_N, S_REST_RET, S_REST_EXIT, S_U, S_EXIT_LABEL, S_T_EXIT, S_T_RET, S_TRACTION, S_TIME = 0, 1, 2, 3, 4, 5, 6, 7, 8
N_SC = 9


@njit(cache=True)
def sdf_one(row, x, out_normal):
    """Signed distance (m) of point x (3,) to the obstacle row; writes the outward unit normal."""
    kind = int(row[0])
    if kind == KIND_SPHERE:
        dx, dy, dz = x[0] - row[2], x[1] - row[3], x[2] - row[4]
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        if dist < 1e-12:
            out_normal[0], out_normal[1], out_normal[2] = 0.0, 0.0, 1.0
        else:
            out_normal[0], out_normal[1], out_normal[2] = dx / dist, dy / dist, dz / dist
        return dist - row[5]
    if kind == KIND_CYLINDER:
        ax, ay, az = row[2], row[3], row[4]
        bx, by, bz = row[5] - ax, row[6] - ay, row[7] - az
        blen = np.sqrt(bx * bx + by * by + bz * bz)
        ux, uy, uz = bx / blen, by / blen, bz / blen
        px, py, pz = x[0] - ax - 0.5 * bx, x[1] - ay - 0.5 * by, x[2] - az - 0.5 * bz
        h = px * ux + py * uy + pz * uz
        rx, ry, rz = px - h * ux, py - h * uy, pz - h * uz
        rr = np.sqrt(rx * rx + ry * ry + rz * rz)
        if rr > 1e-12:
            rx, ry, rz = rx / rr, ry / rr, rz / rr
        else:
            # any direction perpendicular to the axis
            rx, ry, rz = (uy, -ux, 0.0) if abs(uz) < 0.9 else (0.0, uz, -uy)
            nn = np.sqrt(rx * rx + ry * ry + rz * rz)
            rx, ry, rz = rx / nn, ry / nn, rz / nn
        dr = rr - row[8]
        dz = abs(h) - 0.5 * blen
        sz = 1.0 if h >= 0 else -1.0
        if dr > 0 and dz > 0:
            dist = np.sqrt(dr * dr + dz * dz)
            out_normal[0] = (dr * rx + dz * sz * ux) / dist
            out_normal[1] = (dr * ry + dz * sz * uy) / dist
            out_normal[2] = (dr * rz + dz * sz * uz) / dist
            return dist
        if dr >= dz:
            out_normal[0], out_normal[1], out_normal[2] = rx, ry, rz
            return dr
        out_normal[0], out_normal[1], out_normal[2] = sz * ux, sz * uy, sz * uz
        return dz
    if kind == KIND_CAPSULE:
        ax, ay, az = row[2], row[3], row[4]
        bx, by, bz = row[5] - ax, row[6] - ay, row[7] - az
        px, py, pz = x[0] - ax, x[1] - ay, x[2] - az
        t = (px * bx + py * by + pz * bz) / (bx * bx + by * by + bz * bz)
        t = min(max(t, 0.0), 1.0)
        dx, dy, dz = px - t * bx, py - t * by, pz - t * bz
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)
        if dist < 1e-12:
            out_normal[0], out_normal[1], out_normal[2] = 0.0, 0.0, 1.0
        else:
            out_normal[0], out_normal[1], out_normal[2] = dx / dist, dy / dist, dz / dist
        return dist - row[8]
    if kind == KIND_BOX:
        ex0, ex1, ex2 = row[8], row[9], row[10]
        ez0, ez1, ez2 = row[11], row[12], row[13]
        ey0, ey1, ey2 = ez1 * ex2 - ez2 * ex1, ez2 * ex0 - ez0 * ex2, ez0 * ex1 - ez1 * ex0
        px, py, pz = x[0] - row[2], x[1] - row[3], x[2] - row[4]
        lx = px * ex0 + py * ex1 + pz * ex2
        ly = px * ey0 + py * ey1 + pz * ey2
        lz = px * ez0 + py * ez1 + pz * ez2
        qx, qy, qz = abs(lx) - row[5], abs(ly) - row[6], abs(lz) - row[7]
        if qx > 0 or qy > 0 or qz > 0:
            ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
            dist = np.sqrt(ox * ox + oy * oy + oz * oz)
            nx, ny, nz = ox / dist * np.sign(lx), oy / dist * np.sign(ly), oz / dist * np.sign(lz)
        else:
            nx, ny, nz = 0.0, 0.0, 0.0
            if qx >= qy and qx >= qz:
                dist, nx = qx, np.sign(lx)
            elif qy >= qz:
                dist, ny = qy, np.sign(ly)
            else:
                dist, nz = qz, np.sign(lz)
        out_normal[0] = nx * ex0 + ny * ey0 + nz * ez0
        out_normal[1] = nx * ex1 + ny * ey1 + nz * ez1
        out_normal[2] = nx * ex2 + ny * ey2 + nz * ez2
        return dist
    # half-space
    out_normal[0], out_normal[1], out_normal[2] = row[5], row[6], row[7]
    return (x[0] - row[2]) * row[5] + (x[1] - row[3]) * row[6] + (x[2] - row[4]) * row[7]


@njit(cache=True)
def _forces(n, pos, vel, rest, sc, prm, E, vE, R, vR, e1, dR, u_exit_rate, u_ret_rate, obstacles, P, V, L, F, m):
    """Total force F[j] on the extended point list P (ghostR, R, nodes..., E, ghostE); masses m[j]."""
    ds = prm[P_DS]
    npt = n + 4
    # extended points
    for c in range(3):
        P[0, c] = R[c] + ds * dR[c]
        P[1, c] = R[c]
        P[n + 2, c] = E[c]
        P[n + 3, c] = E[c] - ds * e1[c]
        V[0, c] = vR[c]
        V[1, c] = vR[c]
        V[n + 2, c] = vE[c]
        V[n + 3, c] = vE[c]
    for i in range(n):
        for c in range(3):
            P[i + 2, c] = pos[i, c]
            V[i + 2, c] = vel[i, c]
    # rest lengths of the segments P[j] - P[j+1]
    L[0] = ds
    L[1] = sc[S_REST_RET]
    for k in range(n - 1):
        L[k + 2] = rest[k]
    L[n + 1] = sc[S_REST_EXIT]
    L[n + 2] = ds
    for j in range(npt):
        F[j, 0] = 0.0
        F[j, 1] = 0.0
        F[j, 2] = 0.0
    lam, EA, eta = prm[P_LAMBDA], prm[P_EA], prm[P_ETA]
    # axial tension on the real segments j = 1 .. n+1
    for j in range(1, n + 2):
        ex = P[j + 1, 0] - P[j, 0]
        ey = P[j + 1, 1] - P[j, 1]
        ez = P[j + 1, 2] - P[j, 2]
        ln = np.sqrt(ex * ex + ey * ey + ez * ez)
        if ln < 1e-12:
            continue
        rl = L[j]
        eps = ln / rl - 1.0
        rate = (ex * (V[j + 1, 0] - V[j, 0]) + ey * (V[j + 1, 1] - V[j, 1]) + ez * (V[j + 1, 2] - V[j, 2])) / (ln * rl)
        if j == 1:
            rate -= ln * (-u_ret_rate) / (rl * rl)
        elif j == n + 1:
            rate -= ln * u_exit_rate / (rl * rl)
        if eps > 0.0:
            ten = EA * eps
        else:
            ten = prm[P_COMPRESSION] * EA * eps
        ten += eta * rate
        if j == 1:
            sc[S_T_RET] = ten
        if j == n + 1:
            sc[S_T_EXIT] = ten
        fx, fy, fz = ten * ex / ln, ten * ey / ln, ten * ez / ln
        F[j, 0] += fx
        F[j, 1] += fy
        F[j, 2] += fz
        F[j + 1, 0] -= fx
        F[j + 1, 1] -= fy
        F[j + 1, 2] -= fz
    # bending at vertices j = 1 .. n+2 (between segment j-1 and j)
    B = prm[P_B]
    etab = prm[P_ETAB]
    if B > 0.0 or etab > 0.0:
        for j in range(1, n + 3):
            ax = P[j, 0] - P[j - 1, 0]
            ay = P[j, 1] - P[j - 1, 1]
            az = P[j, 2] - P[j - 1, 2]
            bx = P[j + 1, 0] - P[j, 0]
            by = P[j + 1, 1] - P[j, 1]
            bz = P[j + 1, 2] - P[j, 2]
            la = np.sqrt(ax * ax + ay * ay + az * az)
            lb = np.sqrt(bx * bx + by * by + bz * bz)
            if la < 1e-12 or lb < 1e-12:
                continue
            ax, ay, az = ax / la, ay / la, az / la
            bx, by, bz = bx / lb, by / lb, bz / lb
            # a segment squeezed below half its rest length must not stiffen the bending without bound
            la = max(la, 0.5 * L[j - 1])
            lb = max(lb, 0.5 * L[j])
            cth = ax * bx + ay * by + az * bz
            k = B / (0.5 * (L[j - 1] + L[j]))
            gax, gay, gaz = (bx - cth * ax) / la, (by - cth * ay) / la, (bz - cth * az) / la
            gbx, gby, gbz = (ax - cth * bx) / lb, (ay - cth * by) / lb, (az - cth * bz) / lb
            F[j - 1, 0] -= k * gax
            F[j - 1, 1] -= k * gay
            F[j - 1, 2] -= k * gaz
            F[j, 0] += k * (gax - gbx)
            F[j, 1] += k * (gay - gby)
            F[j, 2] += k * (gaz - gbz)
            F[j + 1, 0] += k * gbx
            F[j + 1, 1] += k * gby
            F[j + 1, 2] += k * gbz
            if etab > 0.0:
                # Kelvin-Voigt bending: dissipation (etab / 2 l) |d/dt (t_a x t_b)|^2
                dax = V[j, 0] - V[j - 1, 0]
                day = V[j, 1] - V[j - 1, 1]
                daz = V[j, 2] - V[j - 1, 2]
                dbx = V[j + 1, 0] - V[j, 0]
                dby = V[j + 1, 1] - V[j, 1]
                dbz = V[j + 1, 2] - V[j, 2]
                pa = ax * dax + ay * day + az * daz
                pb = bx * dbx + by * dby + bz * dbz
                tax, tay, taz = (dax - pa * ax) / la, (day - pa * ay) / la, (daz - pa * az) / la
                tbx, tby, tbz = (dbx - pb * bx) / lb, (dby - pb * by) / lb, (dbz - pb * bz) / lb
                # w = ta_dot x t_b + t_a x tb_dot
                wx = (tay * bz - taz * by) + (ay * tbz - az * tby)
                wy = (taz * bx - tax * bz) + (az * tbx - ax * tbz)
                wz = (tax * by - tay * bx) + (ax * tby - ay * tbx)
                kd = etab / (0.5 * (L[j - 1] + L[j]))
                # generalised forces on e_a and e_b: -kd P_a (t_b x w) / la, +kd P_b (t_a x w) / lb
                cx, cy, cz = by * wz - bz * wy, bz * wx - bx * wz, bx * wy - by * wx
                pc = ax * cx + ay * cy + az * cz
                gax, gay, gaz = -kd * (cx - pc * ax) / la, -kd * (cy - pc * ay) / la, -kd * (cz - pc * az) / la
                cx, cy, cz = ay * wz - az * wy, az * wx - ax * wz, ax * wy - ay * wx
                pc = bx * cx + by * cy + bz * cz
                gbx, gby, gbz = kd * (cx - pc * bx) / lb, kd * (cy - pc * by) / lb, kd * (cz - pc * bz) / lb
                F[j - 1, 0] -= gax
                F[j - 1, 1] -= gay
                F[j - 1, 2] -= gaz
                F[j, 0] += gax - gbx
                F[j, 1] += gay - gby
                F[j, 2] += gaz - gbz
                F[j + 1, 0] += gbx
                F[j + 1, 1] += gby
                F[j + 1, 2] += gbz
    # per-node gravity, drag, contact
    rho, cf, cn, d, g = prm[P_RHO], prm[P_CF], prm[P_CN], prm[P_D], prm[P_G]
    kt = 0.5 * rho * cf * np.pi * d
    kn = 0.5 * rho * cn * d
    nrm = np.zeros(3)
    nob = obstacles.shape[0]
    for j in range(2, n + 2):
        share = 0.5 * (L[j - 1] + L[j])
        mj = lam * share
        m[j] = mj
        F[j, 2] -= mj * g
        if kt > 0.0 or kn > 0.0:
            tx = P[j + 1, 0] - P[j - 1, 0]
            ty = P[j + 1, 1] - P[j - 1, 1]
            tz = P[j + 1, 2] - P[j - 1, 2]
            lt = np.sqrt(tx * tx + ty * ty + tz * tz)
            if lt > 1e-12:
                tx, ty, tz = tx / lt, ty / lt, tz / lt
            wx, wy, wz = V[j, 0] - prm[P_WX], V[j, 1] - prm[P_WY], V[j, 2] - prm[P_WZ]
            wt = wx * tx + wy * ty + wz * tz
            nx, ny, nz = wx - wt * tx, wy - wt * ty, wz - wt * tz
            wn = np.sqrt(nx * nx + ny * ny + nz * nz)
            at = kt * abs(wt) * wt * share
            an = kn * wn * share
            F[j, 0] -= at * tx + an * nx
            F[j, 1] -= at * ty + an * ny
            F[j, 2] -= at * tz + an * nz
        for o in range(nob):
            x = P[j]
            dist = sdf_one(obstacles[o], x, nrm)
            pen = prm[P_RCONTACT] - dist
            if pen > 0.0:
                vn = V[j, 0] * nrm[0] + V[j, 1] * nrm[1] + V[j, 2] * nrm[2]
                fn = prm[P_KC] * pen - prm[P_CC] * vn
                if fn < 0.0:
                    fn = 0.0
                tvx, tvy, tvz = V[j, 0] - vn * nrm[0], V[j, 1] - vn * nrm[1], V[j, 2] - vn * nrm[2]
                tv = np.sqrt(tvx * tvx + tvy * tvy + tvz * tvz)
                ff = obstacles[o, 1] * fn / max(tv, prm[P_VREG])
                # regularised Coulomb friction, capped so that one explicit step cannot reverse v_t
                ff = min(ff, 0.5 * mj / prm[P_DT])
                F[j, 0] += fn * nrm[0] - ff * tvx
                F[j, 1] += fn * nrm[1] - ff * tvy
                F[j, 2] += fn * nrm[2] - ff * tvz


@njit(cache=True)
def advance(pos, vel, rest, label, sc, prm, obstacles, E, vE, R, vR, e1, dR, wheel_mps, guide_rate_mps,
            interior_m, dt, P, V, L, F, m):
    """Advance K = len(wheel_mps) steps of dt seconds.

    Per-step inputs, shapes (K, 3) or (K,): eyelet exit/return points E, R and their velocities,
    launch axis e1 (the rope leaves E along it), dR (the unit direction in which the rope runs on into
    the module at R), wheel surface speed, guide travel rate, interior rope length. Returns 0 on success,
    1 if the node capacity is exhausted, 2 if fewer than 3 nodes remain in the air, 3 if a value
    became non-finite or a node outran 20 x the wheel speed + 50 m/s (divergence).
    """
    ds = prm[P_DS]
    lam = prm[P_LAMBDA]
    cap = pos.shape[0]
    K = wheel_mps.shape[0]
    tseg = np.zeros(3)
    vmax = 0.0
    for k in range(K):
        vmax = max(vmax, abs(wheel_mps[k]))
    vlimit2 = (20.0 * vmax + 50.0) ** 2  # no rope node moves at 20 x the wheel speed + 50 m/s
    for k in range(K):
        n = int(sc[S_N])
        u = sc[S_U]
        gdot = guide_rate_mps[k]
        u_exit = u - gdot
        u_ret = u + gdot
        _forces(n, pos, vel, rest, sc, prm, E[k], vE[k], R[k], vR[k], e1[k], dR[k], u_exit, u_ret, obstacles,
                P, V, L, F, m)
        # nodes: symplectic Euler
        for i in range(n):
            j = i + 2
            inv = dt / m[j]
            for c in range(3):
                vel[i, c] += F[j, c] * inv
                pos[i, c] += vel[i, c] * dt
        # interior rope: implicit grip toward the wheel speed, friction limited
        mint = lam * interior_m[k]
        drive = sc[S_T_EXIT] - sc[S_T_RET]
        grip = prm[P_GRIP]
        u_new = (mint * u + dt * (drive + grip * wheel_mps[k])) / (mint + dt * grip)
        trac = grip * (wheel_mps[k] - u_new)
        fmax = prm[P_FMAX]
        if trac > fmax or trac < -fmax:
            trac = fmax if trac > 0 else -fmax
            u_new = u + dt * (drive + trac) / mint
        sc[S_U] = u_new
        sc[S_TRACTION] = trac
        u_exit = u_new - gdot
        u_ret = u_new + gdot
        sc[S_REST_EXIT] += dt * u_exit
        sc[S_REST_RET] -= dt * u_ret
        sc[S_EXIT_LABEL] += dt * u_exit
        sc[S_TIME] += dt
        # births and deaths at the exit
        if sc[S_REST_EXIT] >= 1.5 * ds:
            if n >= cap:
                return 1
            re = sc[S_REST_EXIT]
            f = (re - ds) / re
            # the eyelet lip turns the material into the direction of the exit segment
            # the eyelet at the end of this step (the nodes have moved already)
            ex_ = E[k, 0] + dt * vE[k, 0]
            ey_ = E[k, 1] + dt * vE[k, 1]
            ez_ = E[k, 2] + dt * vE[k, 2]
            tx = pos[n - 1, 0] - ex_
            ty = pos[n - 1, 1] - ey_
            tz = pos[n - 1, 2] - ez_
            tl = np.sqrt(tx * tx + ty * ty + tz * tz)
            if tl > 1e-12:
                tseg[0], tseg[1], tseg[2] = tx / tl, ty / tl, tz / tl
            else:
                tseg[0], tseg[1], tseg[2] = e1[k, 0], e1[k, 1], e1[k, 2]
            for c in range(3):
                vmat = vE[k, c] + u_exit * tseg[c]
                e_c = E[k, c] + dt * vE[k, c]
                pos[n, c] = e_c + f * (pos[n - 1, c] - e_c)
                vel[n, c] = vmat + f * (vel[n - 1, c] - vmat)
            label[n] = sc[S_EXIT_LABEL] - (re - ds)
            rest[n - 1] = ds
            sc[S_REST_EXIT] = re - ds
            n += 1
        elif sc[S_REST_EXIT] < 0.5 * ds:
            if n <= 3:
                return 2
            sc[S_REST_EXIT] += rest[n - 2]
            n -= 1
        # births and deaths at the return
        if sc[S_REST_RET] < 0.5 * ds:
            if n <= 3:
                return 2
            sc[S_REST_RET] += rest[0]
            for i in range(n - 1):
                for c in range(3):
                    pos[i, c] = pos[i + 1, c]
                    vel[i, c] = vel[i + 1, c]
                label[i] = label[i + 1]
            for i in range(n - 2):
                rest[i] = rest[i + 1]
            n -= 1
        elif sc[S_REST_RET] >= 1.5 * ds:
            if n >= cap:
                return 1
            for i in range(n, 0, -1):
                for c in range(3):
                    pos[i, c] = pos[i - 1, c]
                    vel[i, c] = vel[i - 1, c]
                label[i] = label[i - 1]
            for i in range(n - 1, 0, -1):
                rest[i] = rest[i - 1]
            rr = sc[S_REST_RET]
            f = (rr - ds) / rr
            for c in range(3):
                vmat = vR[k, c] + u_ret * dR[k, c]
                r_c = R[k, c] + dt * vR[k, c]
                pos[0, c] = r_c + f * (pos[1, c] - r_c)
                vel[0, c] = vmat + f * (vel[1, c] - vmat)
            label[0] = label[1] - ds
            rest[0] = ds
            sc[S_REST_RET] = rr - ds
            n += 1
        sc[S_N] = n
        if not np.isfinite(pos[0, 0] + pos[n - 1, 2] + u_new):
            return 3
        if k % 64 == 0:
            for i in range(n):
                v2 = vel[i, 0] * vel[i, 0] + vel[i, 1] * vel[i, 1] + vel[i, 2] * vel[i, 2]
                if not v2 < vlimit2:
                    return 3
    return 0
