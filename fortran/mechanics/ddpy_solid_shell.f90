!> The 8-node solid-shell for sheets at large strains and rotations, updated Lagrangian
!> (../docs/theory/solid_shell.md; the choice: ../docs/theory/element_choice.md, SS-AT13).
!>
!> The setting of ddpy_hex8 (reference x_n, increment du, logarithmic strain, material in
!> axes that rotate with the body, the rotated Kirchhoff stress kept, weights W0 of the
!> initial element), with the strain of a Gauss point made differently:
!> - assumed natural strains: the covariant relative Green-Lagrange strain
!>   E_ab = (G_a . D_b + G_b . D_a + D_a . D_b)/2 (G_a = dx_n/dxi_a, D_a = d du/dxi_a) has
!>   its transverse shears E_xi,zeta and E_eta,zeta interpolated from the mid-edge points
!>   (0, +-1, zeta_p) and (+-1, 0, zeta_p) of the Gauss point's level (Dvorkin and Bathe;
!>   Hauptmann and Schweizerhof) and its thickness strain E_zeta,zeta bilinearly from the
!>   four corners of the mid-surface (Betsch and Stein); turned to Cartesian components
!>   with the Jacobian of x_n at the Gauss point, E_as, and dE_as = ln(I + 2 E_as)/2;
!> - 13 enhanced strains added to that strain, dE_hat = dE_as + Gamma alpha,
!>   Gamma_p = (W0_c / W0_p) T_c M(xi_p), M the monomials of the 21 modes of Andelfinger
!>   and Ramm without the transverse shears, T_c the covariant-to-Cartesian strain map of
!>   x_n at the element centre; sum_p W0_p Gamma_p = 0, so constant stresses do no work on
!>   alpha (the patch test).
!> alpha is the enhanced strain of the increment: each evaluation solves
!> f_alpha = sum W0 Gamma^T T = 0 by a local Newton iteration from a start (the previous
!> iterate's alpha), and the tangent is condensed exactly at that solution. The stress
!> kept is pushed forward with the compatible relative deformation of the Gauss point,
!> tau_hat = dU S dU with S = P^T T (P = d dE_as / d E_as) and dF = dR dU, as in
!> ddpy_hex8, so that an increment starts from the converged internal forces.
!> zeta, the third natural coordinate (nodes 1-4 on one face, 5-8 on the other), must be
!> the sheet normal. Voigt order 11, 22, 33, 12, 23, 31 with engineering shear strains.
module ddpy_solid_shell
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_update_checked, material_check, material_yield_stress, &
                           material_prop_count, material_hardening, hill48_equivalent_stress, &
                           material_kinematic, prop_young, prop_hill
  use ddpy_material_mixed, only: material_update_mixed
  use ddpy_hex8, only: pushed_stress
  use ddpy_element_products, only: lower_product, subtract_lower_gram, add_congruence, &
                                   add_pair_product
  use ddpy_log_strain, only: hencky_type, hencky_evaluate, hencky_first, hencky_second, &
                             symmetric_eigen
  implicit none
  private
  public :: solid_shell_element

  !> Enhanced parameters per element.
  integer, parameter, public :: shell_modes = 13
  !> Status values of solid_shell_element: those of hex8_element (ok, inverted, material
  !> update failed) and the local iteration on alpha that did not converge.
  integer, parameter, public :: shell_ok = 0, shell_inverted = 1, shell_material_failed = 2, &
                                shell_not_converged = 5

  !> Local iteration on alpha: converged when the last correction changes the enhanced
  !> strain of every point by at most local_tolerance of the strain scale (the largest
  !> strain increment, or stress over Young's modulus, of the element's points); the
  !> forces take that last correction to first order, so they are a function of du to the
  !> square of it.
  real(wp), parameter :: local_tolerance = 1.0e-10_wp
  integer, parameter :: local_iterations = 25, local_searches = 4
  !> The elastic shortcut of the local iteration keeps this relative margin below the
  !> yield surface (material_update_checked's own margin is 1e-12 above it), so that a
  !> point it calls elastic is elastic to the material update too.
  real(wp), parameter :: elastic_margin = -1.0e-10_wp

  real(wp), parameter :: corner(3, 8) = reshape([ &
    -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, &
    -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, &
    1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp], [3, 8])
  real(wp), parameter :: gauss = 0.577350269189625764509148780502_wp
  !> The 12 sampling points of the assumed strains: per level zeta = -+gauss, the points
  !> (0, -1), (0, 1) of E_31 and (-1, 0), (1, 0) of E_23; then the mid-surface corners
  !> (-1, -1), (1, -1), (1, 1), (-1, 1) of E_33.
  real(wp), parameter :: sample(3, 12) = reshape([ &
    0.0_wp, -1.0_wp, -gauss, 0.0_wp, 1.0_wp, -gauss, -1.0_wp, 0.0_wp, -gauss, &
    1.0_wp, 0.0_wp, -gauss, &
    0.0_wp, -1.0_wp, gauss, 0.0_wp, 1.0_wp, gauss, -1.0_wp, 0.0_wp, gauss, &
    1.0_wp, 0.0_wp, gauss, &
    -1.0_wp, -1.0_wp, 0.0_wp, 1.0_wp, -1.0_wp, 0.0_wp, 1.0_wp, 1.0_wp, 0.0_wp, &
    -1.0_wp, 1.0_wp, 0.0_wp], [3, 12])
  !> The enhanced modes: covariant Voigt component (modes first(c) .. first(c + 1) - 1 act
  !> on component c = 11, 22, 33, 12) and exponents of xi, eta, zeta.
  integer, parameter :: mode_component(shell_modes) = [1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4, 4]
  integer, parameter :: first(5) = [1, 4, 7, 10, 14]
  integer, parameter :: mode_power(3, shell_modes) = reshape([ &
    1, 0, 0, 1, 1, 0, 1, 0, 1, &
    0, 1, 0, 1, 1, 0, 0, 1, 1, &
    0, 0, 1, 1, 0, 1, 0, 1, 1, &
    1, 0, 0, 0, 1, 0, 1, 0, 1, 0, 1, 1], [3, shell_modes])

contains

  ! The small dense matrices: one source with the other element (see the file).
  include "ddpy_small_matrix.inc"

  !> Right stretch dU and its inverse of a deformation gradient fg (det > 0), from the
  !> eigenvalues of its Green-Lagrange strain.
  pure subroutine stretch(fg, u, u_inv)
    real(wp), intent(in) :: fg(3, 3)
    real(wp), intent(out) :: u(3, 3), u_inv(3, 3)
    real(wp) :: c(3, 3), values(3), vectors(3, 3), root(3)
    integer :: i, j
    c = 0.5_wp*matmul(transpose(fg), fg)
    do i = 1, 3
      c(i, i) = c(i, i) - 0.5_wp
    end do
    call symmetric_eigen(c, values, vectors)
    root = sqrt(1.0_wp + 2.0_wp*values)
    do j = 1, 3
      do i = 1, 3
        u(i, j) = sum(root*vectors(i, :)*vectors(j, :))
        u_inv(i, j) = sum(vectors(i, :)*vectors(j, :)/root)
      end do
    end do
  end subroutine stretch

  !> In-place Cholesky factor (lower triangle) of a symmetric n x n matrix; ok false when
  !> it is not positive definite. By columns (left-looking), so that every update runs
  !> down a contiguous column.
  pure subroutine cholesky(n, a, ok)
    integer, intent(in) :: n
    real(wp), intent(inout) :: a(n, n)
    logical, intent(out) :: ok
    integer :: j, k
    ok = .true.
    do j = 1, n
      do k = 1, j - 1
        a(j:n, j) = a(j:n, j) - a(j:n, k)*a(j, k)
      end do
      if (.not. a(j, j) > 0.0_wp) then
        ok = .false.
        return
      end if
      a(j, j) = sqrt(a(j, j))
      a(j + 1:n, j) = a(j + 1:n, j)/a(j, j)
    end do
  end subroutine cholesky

  !> b = L^-1 b for the lower factor L (forward substitution by columns), one right-hand
  !> side.
  pure subroutine forward(n, l, b)
    integer, intent(in) :: n
    real(wp), intent(in) :: l(n, n)
    real(wp), intent(inout) :: b(n)
    integer :: j
    do j = 1, n
      b(j) = b(j)/l(j, j)
      b(j + 1:n) = b(j + 1:n) - l(j + 1:n, j)*b(j)
    end do
  end subroutine forward

  !> y = b L^-T for the lower factor L, b of 24 rows: (L^-1 b^T)^T by columns.
  pure subroutine forward_rows(n, l, y)
    integer, intent(in) :: n
    real(wp), intent(in) :: l(n, n)
    real(wp), intent(inout) :: y(24, n)
    integer :: i, j
    do i = 1, n
      do j = 1, i - 1
        y(:, i) = y(:, i) - l(i, j)*y(:, j)
      end do
      y(:, i) = y(:, i)/l(i, i)
    end do
  end subroutine forward_rows

  !> b = L^-T b (back substitution), one right-hand side.
  pure subroutine backward(n, l, b)
    integer, intent(in) :: n
    real(wp), intent(in) :: l(n, n)
    real(wp), intent(inout) :: b(n)
    integer :: i
    do i = n, 1, -1
      b(i) = (b(i) - dot_product(l(i + 1:n, i), b(i + 1:n)))/l(i, i)
    end do
  end subroutine backward

  !> Internal force, tangent, trial material state and enhanced parameters of one element
  !> over an increment: the arguments of hex8_element (ddpy_hex8) and alpha_in, the start
  !> of the local iteration (the previous iterate's alpha; zero at the start of an
  !> increment), alpha its solution; back_old, back the backstress (mixed hardening only;
  !> back from the last evaluation of the local iteration, like ep, pushed forward as the
  !> stress). Status shell_ok, shell_inverted (det J0, det J or
  !> det dF <= 0 at a Gauss point, or I + 2 E_as not positive definite),
  !> shell_material_failed (a return mapping failed, or K_aa is not positive definite) or
  !> shell_not_converged (the local iteration).
  pure subroutine solid_shell_element(x0, xn, du, props, axes_old, stress_old, ep_old, &
                                      strain_old, back_old, alpha_in, want_tangent, f, k, &
                                      stress, ep, strain, axes, back, alpha, status)
    real(wp), intent(in) :: x0(3, 8), xn(3, 8), du(3, 8), props(material_prop_count)
    real(wp), intent(in) :: axes_old(3, 3, 8), stress_old(6, 8), ep_old(8), strain_old(6, 8), &
                            back_old(6, 8), alpha_in(shell_modes)
    logical, intent(in) :: want_tangent
    real(wp), intent(out) :: f(24), k(24, 24), stress(6, 8), ep(8), strain(6, 8), &
                             axes(3, 3, 8), back(6, 8), alpha(shell_modes)
    integer, intent(out) :: status
    type(hencky_type) :: hk(8)
    ! Per Gauss point: bt = (d E_as / d du)^T by dof; pm = d dE_as / d E_as; rot the strain
    ! map into the material axes of x_n; de0 = rot dE_as; the enhanced strain rot Gamma =
    ! g4 S with g4 the four columns (W0_c / W0_p) rot T_c(:, 1:4) and S the monomials mono
    ! of each mode in its component's row (see grouped); dg4 = D g4; the material's stress
    ! and tangent; rk the columns of the tangent.
    real(wp) :: bt(24, 6, 8), pm(6, 6, 8), rot(6, 6, 8), g4(6, 4, 8), &
                de0(6, 8), dg4(6, 4, 8), s_mat(6, 8), d_mat(6, 6, 8), rk(24, 6, 8), &
                tmap(6, 6, 8), w0(8), fgs(3, 3, 8)
    ! The sampling points: the sampled strain and its derivative.
    real(wp) :: eq(12), bq(24, 12)
    real(wp) :: gb(3, 3), db(3, 3), gc(3, 3), inv(3, 3), tc(6, 6), w0c, vj, &
                ecov(6), bcov(24, 6), e_as(6), ratio, xi(3), wgt(4), kaa(shell_modes, &
                shell_modes), fa(shell_modes), dalpha(shell_modes), kua(24, shell_modes), &
                cq(3, 3, 20), kg(8, 8), ga(8, 2), gb8(8, 2), mmat(6, 6), a_hat(6), s6(6), &
                t_mat(6), tg(6), rp(6, 6), rdg(6, 4), bg(24, 4), a4(4), u(3, 3), u_inv(3, 3), &
                s3(3, 3), scale, change, yield_floor, zero24(24), s_start, &
                s_end, step, lo, hi, s_lo, s_hi, x_mat(6, 8), stretches(3, 3, 8)
    integer :: p, q, a, c, i, j, m, col, level, iteration, mstatus, off, search
    logical :: ok, converged, elastic, kinematic
    ! The shape functions' natural derivatives dN_a/dxi_j (8, 3) at the fixed points of the
    ! element, constants: at the centre, at the Gauss points gauss*corner(:, p) and at the
    ! sampling points; and the enhanced modes' monomials at the Gauss points (their
    ! exponents are 0 or 1).
    real(wp), parameter :: dn_centre(8, 3) = 0.125_wp*transpose(corner)
    real(wp), parameter :: dn_gauss(8, 3, 8) = reshape([(((0.125_wp*corner(j, a) &
      *(1.0_wp + corner(mod(j, 3) + 1, a)*gauss*corner(mod(j, 3) + 1, p)) &
      *(1.0_wp + corner(mod(j + 1, 3) + 1, a)*gauss*corner(mod(j + 1, 3) + 1, p)), &
      a = 1, 8), j = 1, 3), p = 1, 8)], [8, 3, 8])
    real(wp), parameter :: dn_sample(8, 3, 12) = reshape([(((0.125_wp*corner(j, a) &
      *(1.0_wp + corner(mod(j, 3) + 1, a)*sample(mod(j, 3) + 1, p)) &
      *(1.0_wp + corner(mod(j + 1, 3) + 1, a)*sample(mod(j + 1, 3) + 1, p)), &
      a = 1, 8), j = 1, 3), p = 1, 12)], [8, 3, 12])
    real(wp), parameter :: mono_gauss(shell_modes, 8) = reshape([((product(merge( &
      gauss*corner(:, p), 1.0_wp, mode_power(:, m) == 1)), m = 1, shell_modes), p = 1, 8)], &
      [shell_modes, 8])

    f = 0.0_wp
    k = 0.0_wp
    stress = stress_old
    ep = ep_old
    strain = strain_old
    axes = axes_old
    back = back_old
    alpha = alpha_in
    status = shell_ok
    kinematic = material_kinematic(props)

    ! The element centre of x_n: the map of the enhanced strains; W0_c of the initial one.
    gc = matmul(xn, dn_centre)
    vj = det3(gc)
    w0c = det3(matmul(x0, dn_centre))
    if (vj <= 0.0_wp .or. w0c <= 0.0_wp) then
      status = shell_inverted
      return
    end if
    call strain_map(inverse3(gc, vj), tc)

    ! The sampling points: E_31 (engineering, 2 E_13) at 1, 2 and 5, 6; E_23 at 3, 4 and
    ! 7, 8; E_33 at 9 .. 12, with their derivatives by the dofs, on g = G + D.
    do q = 1, 12
      gb = matmul(xn, dn_sample(:, :, q))
      db = matmul(du, dn_sample(:, :, q))
      select case (mod(q - 1, 4) + 1 + merge(4, 0, q > 8))
      case (1, 2)
        i = 1
        j = 3
      case (3, 4)
        i = 2
        j = 3
      case default
        i = 3
        j = 3
      end select
      if (i == j) then
        eq(q) = dot_product(gb(:, 3), db(:, 3)) + 0.5_wp*dot_product(db(:, 3), db(:, 3))
      else
        eq(q) = dot_product(gb(:, i), db(:, j)) + dot_product(gb(:, j), db(:, i)) &
                + dot_product(db(:, i), db(:, j))
      end if
      gb = gb + db
      do a = 1, 8
        if (i == j) then
          bq(3*a - 2:3*a, q) = gb(:, 3)*dn_sample(a, 3, q)
        else
          bq(3*a - 2:3*a, q) = gb(:, j)*dn_sample(a, i, q) + gb(:, i)*dn_sample(a, j, q)
        end if
      end do
    end do

    ! The Gauss points: assumed strain, its logarithm and derivatives, enhanced modes.
    do p = 1, 8
      xi = gauss*corner(:, p)
      level = merge(1, 2, corner(3, p) < 0.0_wp)
      off = 4*(level - 1)
      w0(p) = det3(matmul(x0, dn_gauss(:, :, p)))
      gb = matmul(xn, dn_gauss(:, :, p))
      vj = det3(gb)
      if (w0(p) <= 0.0_wp .or. vj <= 0.0_wp) then
        status = shell_inverted
        return
      end if
      inv = inverse3(gb, vj)
      db = matmul(du, dn_gauss(:, :, p))
      ! Compatible relative deformation dF = I + D J^-1 (for the polar decomposition).
      fgs(:, :, p) = matmul(db, inv)
      do i = 1, 3
        fgs(i, i, p) = fgs(i, i, p) + 1.0_wp
      end do
      if (det3(fgs(:, :, p)) <= 0.0_wp) then
        status = shell_inverted
        return
      end if
      ! Covariant strain: in-plane at the point, the rest interpolated.
      ecov(1) = dot_product(gb(:, 1), db(:, 1)) + 0.5_wp*dot_product(db(:, 1), db(:, 1))
      ecov(2) = dot_product(gb(:, 2), db(:, 2)) + 0.5_wp*dot_product(db(:, 2), db(:, 2))
      ecov(4) = dot_product(gb(:, 1), db(:, 2)) + dot_product(gb(:, 2), db(:, 1)) &
                + dot_product(db(:, 1), db(:, 2))
      gb = gb + db
      do a = 1, 8
        col = 3*a - 2
        bcov(col:col + 2, 1) = gb(:, 1)*dn_gauss(a, 1, p)
        bcov(col:col + 2, 2) = gb(:, 2)*dn_gauss(a, 2, p)
        bcov(col:col + 2, 4) = gb(:, 1)*dn_gauss(a, 2, p) + gb(:, 2)*dn_gauss(a, 1, p)
      end do
      wgt = 0.25_wp*(1.0_wp + corner(1, 1:4)*xi(1))*(1.0_wp + corner(2, 1:4)*xi(2))
      ecov(3) = dot_product(wgt, eq(9:12))
      bcov(:, 3) = matmul(bq(:, 9:12), wgt)
      ecov(5) = 0.5_wp*((1.0_wp - xi(1))*eq(off + 3) + (1.0_wp + xi(1))*eq(off + 4))
      bcov(:, 5) = 0.5_wp*((1.0_wp - xi(1))*bq(:, off + 3) + (1.0_wp + xi(1))*bq(:, off + 4))
      ecov(6) = 0.5_wp*((1.0_wp - xi(2))*eq(off + 1) + (1.0_wp + xi(2))*eq(off + 2))
      bcov(:, 6) = 0.5_wp*((1.0_wp - xi(2))*bq(:, off + 1) + (1.0_wp + xi(2))*bq(:, off + 2))
      ! Cartesian components on x_n.
      call strain_map(inv, tmap(:, :, p))
      e_as = matmul(tmap(:, :, p), ecov)
      do c = 1, 6
        bt(:, c, p) = by_dofs(bcov, tmap(c, :, p))
      end do
      call hencky_evaluate(e_as, hk(p))
      if (.not. minval(hk(p)%mu) > -1.0_wp) then
        status = shell_inverted
        return
      end if
      call hencky_first(hk(p), pm(:, :, p))
      call strain_map(axes_old(:, :, p), rot(:, :, p))
      de0(:, p) = matmul(rot(:, :, p), hk(p)%strain)
      ! Enhanced modes in the material axes.
      ratio = w0c/w0(p)
      do c = 1, 4
        g4(:, c, p) = ratio*(rot(:, 1, p)*tc(1, c) + rot(:, 2, p)*tc(2, c) + rot(:, 3, p)*tc(3, c) &
                             + rot(:, 4, p)*tc(4, c) + rot(:, 5, p)*tc(5, c) + rot(:, 6, p)*tc(6, c))
      end do
    end do

    ! The local iteration on alpha, a Newton iteration on f_alpha = 0, each evaluation a
    ! material update of the 8 points. f_alpha is the gradient of the increment's
    ! potential in alpha (backward Euler of associative plasticity, convex with
    ! hardening), so a step that overshoots along its direction d (s(t) = d . f_alpha(alpha
    ! + t d) changes sign and ends above half of |s(0)|) is cut back by secant steps on s,
    ! as the energy line search of the Newton loop does; full steps cycle between elastic
    ! and plastic states of a point when the start is far from the solution.
    if (material_check(props) /= 0) then
      status = shell_material_failed
      return
    end if
    yield_floor = material_yield_stress(props, 0.0_wp)
    call local_state(props, kinematic, yield_floor, stress_old, back_old, ep_old, de0, g4, mono_gauss, w0, alpha, s_mat, ep, &
                     d_mat, dg4, strain, x_mat, fa, kaa, scale, elastic, mstatus)
    if (mstatus /= shell_ok) then
      status = mstatus
      return
    end if
    converged = .false.
    do iteration = 1, local_iterations
      call cholesky(shell_modes, kaa, ok)
      if (.not. ok) then
        status = shell_material_failed
        return
      end if
      dalpha = -fa
      call forward(shell_modes, kaa, dalpha)
      call backward(shell_modes, kaa, dalpha)
      change = 0.0_wp
      do p = 1, 8
        a4 = grouped(mono_gauss(:, p), dalpha)
        change = max(change, maxval(abs(g4(:, 1, p)*a4(1) + g4(:, 2, p)*a4(2) &
                                        + g4(:, 3, p)*a4(3) + g4(:, 4, p)*a4(4))))
      end do
      if (change <= local_tolerance*scale) then
        converged = .true.
        exit
      end if
      ! Every point elastic, here and at alpha + dalpha: f_alpha is linear in alpha there,
      ! so dalpha is its exact solution and the forces below (to first order in dalpha) are
      ! exact; evaluating the material again would only confirm it (most elements of a
      ! forming blank, in most iterations).
      if (elastic) then
        if (stays_elastic(props, yield_floor, ep_old, back_old, s_mat, dg4, mono_gauss, &
                          dalpha)) then
          converged = .true.
          exit
        end if
      end if
      ! Near a point's yield surface the plastic tangent is soft along the flow, and a full
      ! step can go far beyond where the point unloads: at most the element's strain scale.
      if (change > scale) dalpha = (scale/change)*dalpha
      s_start = dot_product(dalpha, fa)
      step = 1.0_wp
      call local_state(props, kinematic, yield_floor, stress_old, back_old, ep_old, de0, g4, mono_gauss, w0, alpha + dalpha, &
                       s_mat, ep, d_mat, dg4, strain, x_mat, fa, kaa, scale, elastic, mstatus)
      if (mstatus /= shell_ok) then
        status = mstatus
        return
      end if
      s_end = dot_product(dalpha, fa)
      if (s_end > 0.0_wp .and. s_end > -0.5_wp*s_start) then
        ! Secant steps on s within the bracket, until |s| <= |s(0)|/2.
        lo = 0.0_wp
        s_lo = s_start
        hi = 1.0_wp
        s_hi = s_end
        do search = 1, local_searches
          step = hi - s_hi*(hi - lo)/(s_hi - s_lo)
          step = min(max(step, lo + 0.1_wp*(hi - lo)), hi - 0.1_wp*(hi - lo))
          call local_state(props, kinematic, yield_floor, stress_old, back_old, ep_old, de0, g4, mono_gauss, w0, &
                           alpha + step*dalpha, s_mat, ep, d_mat, dg4, strain, x_mat, fa, &
                           kaa, scale, elastic, mstatus)
          if (mstatus /= shell_ok) then
            status = mstatus
            return
          end if
          s_end = dot_product(dalpha, fa)
          if (abs(s_end) <= -0.5_wp*s_start) exit
          if (s_end > 0.0_wp) then
            hi = step
            s_hi = s_end
          else
            lo = step
            s_lo = s_end
          end if
        end do
      end if
      alpha = alpha + step*dalpha
    end do
    if (.not. converged) then
      status = shell_not_converged
      return
    end if
    alpha = alpha + dalpha

    ! Forces with the last correction to first order, t = s + D Gamma dalpha; the state at
    ! the end of the increment as in ddpy_hex8: strain, the axes turned by dR and the
    ! rotated Kirchhoff stress dU S dU of the compatible dF = dR dU.
    do p = 1, 8
      a4 = grouped(mono_gauss(:, p), dalpha)
      t_mat = s_mat(:, p) + matmul(dg4(:, :, p), a4)
      strain(:, p) = strain_old(:, p) + strain(:, p) + matmul(g4(:, :, p), a4)
      do c = 1, 6
        tg(c) = dot_product(rot(:, c, p), t_mat)
      end do
      s_mat(:, p) = tg  ! from here the stress in global axes
      do c = 1, 6
        s6(c) = dot_product(tg, pm(:, c, p))
      end do
      f = f + w0(p)*by_dofs(bt(:, :, p), s6)
      call stretch(fgs(:, :, p), u, u_inv)
      stretches(:, :, p) = u  ! for the backstress: one call of stretch stays inline
      axes(:, :, p) = product3(product3(fgs(:, :, p), u_inv), axes_old(:, :, p))
      u = product3(u, product3(stress_tensor(s6), u))
      s3 = product3(u, axes_old(:, :, p))
      do j = 1, 3
        do i = 1, 3
          u(i, j) = dot_product(axes_old(:, i, p), s3(:, j))
        end do
      end do
      stress(:, p) = [u(1, 1), u(2, 2), u(3, 3), 0.5_wp*(u(1, 2) + u(2, 1)), &
                      0.5_wp*(u(2, 3) + u(3, 2)), 0.5_wp*(u(3, 1) + u(1, 3))]
    end do
    ! The backstress by the stress's own map, after the loop above: inside it, its branch
    ! made GCC keep the isotropic path's small helpers out of line (docs/theory/material.md,
    ! "Its cost when it is off").
    if (kinematic) call push_backstress(stretches, rot, pm, x_mat, axes_old, back)
    if (.not. want_tangent) return

    ! The tangent. Per point the material and logarithm part b^T (W0 P^T D P + L(A)) b
    ! (A = W0 T, L = A : d2 dE / d E_as2), six columns of rk for one product at the end;
    ! the coupling K_ua = sum W0 b^T P^T D Gamma; the geometric part A : d2 E_as as
    ! contravariant stress coefficients (P^T A turned by T_p^T) at the Gauss point (in
    ! plane) and at the sampling points (interpolation weights of the assumed strains).
    kua = 0.0_wp
    cq = 0.0_wp
    do p = 1, 8
      xi = gauss*corner(:, p)
      off = 4*merge(0, 1, corner(3, p) < 0.0_wp)
      a_hat = w0(p)*s_mat(:, p)
      call hencky_second(hk(p), a_hat, mmat)
      do j = 1, 6
        rp(:, j) = rot(:, 1, p)*pm(1, j, p) + rot(:, 2, p)*pm(2, j, p) + rot(:, 3, p)*pm(3, j, p) &
                   + rot(:, 4, p)*pm(4, j, p) + rot(:, 5, p)*pm(5, j, p) + rot(:, 6, p)*pm(6, j, p)
      end do
      call add_congruence(w0(p), rp, d_mat(:, :, p), mmat)
      do i = 1, 6
        rk(:, i, p) = by_dofs(bt(:, :, p), mmat(i, :))
      end do
      do c = 1, 4
        do i = 1, 6
          rdg(i, c) = w0(p)*dot_product(rp(:, i), dg4(:, c, p))
        end do
      end do
      ! bg = bt rdg written out: a second call of by_dofs here kept both out of line
      ! (docs/theory/material.md, "Its cost when it is off").
      do c = 1, 4
        bg(:, c) = bt(:, 1, p)*rdg(1, c) + bt(:, 2, p)*rdg(2, c) + bt(:, 3, p)*rdg(3, c) &
                   + bt(:, 4, p)*rdg(4, c) + bt(:, 5, p)*rdg(5, c) + bt(:, 6, p)*rdg(6, c)
      end do
      do m = 1, shell_modes
        kua(:, m) = kua(:, m) + mono_gauss(m, p)*bg(:, mode_component(m))
      end do
      do c = 1, 6
        s6(c) = dot_product(a_hat, pm(:, c, p))
      end do
      ecov = matmul(s6, tmap(:, :, p))  ! contravariant stress, Voigt
      cq(1, 1, p) = ecov(1)
      cq(2, 2, p) = ecov(2)
      cq(1, 2, p) = ecov(4)
      cq(2, 1, p) = ecov(4)
      wgt = 0.25_wp*(1.0_wp + corner(1, 1:4)*xi(1))*(1.0_wp + corner(2, 1:4)*xi(2))
      cq(3, 3, 17:20) = cq(3, 3, 17:20) + ecov(3)*wgt
      do i = 1, 2  ! E_31 at (0, -+1), E_23 at (-+1, 0) of the level
        q = 8 + off + i
        cq(1, 3, q) = cq(1, 3, q) + 0.5_wp*(1.0_wp + (2*i - 3)*xi(2))*ecov(6)
        q = 8 + off + 2 + i
        cq(2, 3, q) = cq(2, 3, q) + 0.5_wp*(1.0_wp + (2*i - 3)*xi(1))*ecov(5)
      end do
    end do
    zero24 = 0.0_wp
    call lower_product(bt, rk, zero24, zero24, k)
    ! kg = sum of g c g^T over the points, g their shape derivatives, c the stress
    ! coefficients, each with only the terms it has: the in-plane pair at the Gauss points,
    ! a shear with the thickness direction at the first eight sampling points, the
    ! thickness stress at the last four.
    kg = 0.0_wp
    do q = 1, 8
      ga(:, 1) = dn_gauss(:, 1, q)*cq(1, 1, q) + dn_gauss(:, 2, q)*cq(1, 2, q)
      ga(:, 2) = dn_gauss(:, 1, q)*cq(1, 2, q) + dn_gauss(:, 2, q)*cq(2, 2, q)
      call add_pair_product(ga, dn_gauss(:, 1:2, q), kg)
    end do
    do q = 1, 8
      i = merge(1, 2, mod(q - 1, 4) < 2)  ! E_31 at 1, 2, 5, 6; E_23 at 3, 4, 7, 8
      ga(:, 1) = cq(i, 3, q + 8)*dn_sample(:, i, q)
      ga(:, 2) = cq(i, 3, q + 8)*dn_sample(:, 3, q)
      gb8(:, 1) = dn_sample(:, 3, q)
      gb8(:, 2) = dn_sample(:, i, q)
      call add_pair_product(ga, gb8, kg)
    end do
    do q = 9, 12
      ga(:, 1) = cq(3, 3, q + 8)*dn_sample(:, 3, q)
      ga(:, 2) = 0.0_wp
      gb8(:, 1) = dn_sample(:, 3, q)
      gb8(:, 2) = 0.0_wp
      call add_pair_product(ga, gb8, kg)
    end do
    ! Condensation: K - K_ua K_aa^-1 K_ua^T = K - Y Y^T, Y = K_ua L^-T.
    call forward_rows(shell_modes, kaa, kua)
    call subtract_lower_gram(kua, k)
    do j = 1, 8
      do i = j, 8
        do c = 1, 3
          k(3*(i - 1) + c, 3*(j - 1) + c) = k(3*(i - 1) + c, 3*(j - 1) + c) + kg(i, j)
        end do
      end do
    end do
    do j = 2, 24
      do i = 1, j - 1
        k(i, j) = k(j, i)
      end do
    end do


  end subroutine solid_shell_element

  !> The backstress x_mat (material axes, at the end of the local iteration) pushed to
  !> the end of the increment as the stress is (ddpy_hex8's pushed_stress): turned by rot,
  !> mapped by pm, rotated with the point's stretch.
  pure subroutine push_backstress(stretches, rot, pm, x_mat, axes_old, back)
    real(wp), intent(in) :: stretches(3, 3, 8), rot(6, 6, 8), pm(6, 6, 8), x_mat(6, 8), &
                            axes_old(3, 3, 8)
    real(wp), intent(out) :: back(6, 8)
    real(wp) :: xg(6), x6(6)
    integer :: p, c
    do p = 1, 8
      do c = 1, 6
        xg(c) = dot_product(rot(:, c, p), x_mat(:, p))
      end do
      do c = 1, 6
        x6(c) = dot_product(xg, pm(:, c, p))
      end do
      back(:, p) = pushed_stress(stretches(:, :, p), x6, axes_old(:, :, p))
    end do
  end subroutine push_backstress

  !> Whether every point's stress s_mat + dg4 grouped(mono, dalpha), the elastic prediction
  !> at alpha + dalpha, relative to its backstress back_old (zeros without mixed hardening,
  !> so the isotropic test to the bit), is inside the yield surface of its ep_old, by the
  !> test of material_update_checked (the same trial stress, up to rounding).
  pure logical function stays_elastic(props, yield_floor, ep_old, back_old, s_mat, dg4, mono, &
                                      dalpha)
    real(wp), intent(in) :: props(material_prop_count), yield_floor, ep_old(8), &
                            back_old(6, 8), s_mat(6, 8), dg4(6, 4, 8), mono(shell_modes, 8), &
                            dalpha(shell_modes)
    real(wp) :: sigma, y, slope
    integer :: p
    stays_elastic = .false.
    do p = 1, 8
      sigma = hill48_equivalent_stress(props(prop_hill:prop_hill + 5), &
                                       s_mat(:, p) - back_old(:, p) &
                                       + matmul(dg4(:, :, p), grouped(mono(:, p), dalpha)))
      if (sigma > yield_floor*(1.0_wp + elastic_margin)) then
        call material_hardening(props, ep_old(p), y, slope)
        if (sigma > y*(1.0_wp + elastic_margin)) return
      end if
    end do
    stays_elastic = .true.
  end function stays_elastic

  !> The enhanced strain's four component amplitudes of the parameters v at a point with
  !> monomials mono: a4(c) = sum of mono(m) v(m) over the modes m of component c.
  pure function grouped(mono, v) result(a4)
    real(wp), intent(in) :: mono(shell_modes), v(shell_modes)
    real(wp) :: a4(4)
    integer :: c
    do c = 1, 4
      a4(c) = dot_product(mono(first(c):first(c + 1) - 1), v(first(c):first(c + 1) - 1))
    end do
  end function grouped

  !> The material at the 8 points of an element for the enhanced parameters at: the strain
  !> increment de = de0 + g4 grouped(mono, at) (material axes), the material's stress
  !> s_mat, plastic strain ep and tangent d_mat, dg4 = d_mat g4, f_alpha (fa) and K_aa
  !> (kaa; from the 4 x 4 blocks g4^T D g4 of the points), the strain scale of the
  !> local iteration's tolerance (the largest strain increment or stress over Young's
  !> modulus), and whether every point stayed elastic; status shell_ok or
  !> shell_material_failed.
  pure subroutine local_state(props, kinematic, yield_floor, stress_old, back_old, ep_old, &
                              de0, g4, mono, w0, at, s_mat, ep, d_mat, dg4, de, back, fa, kaa, &
                              scale, elastic, status)
    real(wp), intent(in) :: props(material_prop_count), yield_floor, stress_old(6, 8), &
                            back_old(6, 8), ep_old(8), de0(6, 8), g4(6, 4, 8), &
                            mono(shell_modes, 8), w0(8), at(shell_modes)
    logical, intent(in) :: kinematic
    real(wp), intent(out) :: s_mat(6, 8), ep(8), d_mat(6, 6, 8), dg4(6, 4, 8), de(6, 8), &
                             back(6, 8), fa(shell_modes), kaa(shell_modes, shell_modes), scale
    logical, intent(out) :: elastic
    integer, intent(out) :: status
    real(wp) :: h(4, 4), gs(4), wm(shell_modes), hw(shell_modes, 4)
    integer :: p, m, n, c, mstatus
    logical :: plastic
    status = shell_ok
    elastic = .true.
    scale = 0.0_wp
    fa = 0.0_wp
    kaa = 0.0_wp
    do p = 1, 8
      de(:, p) = de0(:, p) + matmul(g4(:, :, p), grouped(mono(:, p), at))
      if (kinematic) then
        ! The element's tangent is symmetric: the material's enters by its symmetric part.
        call material_update_mixed(props, yield_floor, stress_old(:, p), back_old(:, p), &
                                   ep_old(p), de(:, p), s_mat(:, p), back(:, p), ep(p), &
                                   d_mat(:, :, p), plastic, mstatus)
        d_mat(:, :, p) = 0.5_wp*(d_mat(:, :, p) + transpose(d_mat(:, :, p)))
      else
        call material_update_checked(props, yield_floor, stress_old(:, p), ep_old(p), &
                                     de(:, p), s_mat(:, p), ep(p), d_mat(:, :, p), plastic, &
                                     mstatus)
      end if
      if (mstatus > 0) then
        status = shell_material_failed
        return
      end if
      elastic = elastic .and. .not. plastic
      scale = max(scale, maxval(abs(de(:, p))), maxval(abs(s_mat(:, p)))/props(prop_young))
      do c = 1, 4
        dg4(:, c, p) = d_mat(:, 1, p)*g4(1, c, p) + d_mat(:, 2, p)*g4(2, c, p) &
                       + d_mat(:, 3, p)*g4(3, c, p) + d_mat(:, 4, p)*g4(4, c, p) &
                       + d_mat(:, 5, p)*g4(5, c, p) + d_mat(:, 6, p)*g4(6, c, p)
      end do
      do c = 1, 4
        do m = 1, 4
          h(m, c) = dot_product(g4(:, m, p), dg4(:, c, p))
        end do
        gs(c) = dot_product(s_mat(:, p), g4(:, c, p))
      end do
      wm = w0(p)*mono(:, p)
      ! hw(:, c): the column of h of component c spread over the modes, times wm; whole
      ! columns of K_aa (both triangles) in vector sums rather than the lower triangle
      ! entry by entry.
      do c = 1, 4
        hw(:, c) = wm*h(mode_component, c)
      end do
      fa = fa + wm*gs(mode_component)
      do n = 1, shell_modes
        kaa(:, n) = kaa(:, n) + mono(n, p)*hw(:, mode_component(n))
      end do
    end do
  end subroutine local_state

end module ddpy_solid_shell
