!> The 8-node hexahedron at large strains and rotations, updated Lagrangian
!> (../docs/theory/solid.md).
!>
!> Each increment is referred to the last converged configuration x_n: the relative
!> deformation gradient dF = I + grad_xn du has the Green-Lagrange strain E_GL and the
!> logarithmic strain dE = ln(dU) (ddpy_log_strain), whose derivatives are exact, so the
!> tangent is consistent. Against volumetric locking, the mean dilatation: the volumetric
!> part of dE (ln det dF) is replaced by its volume average over the element,
!> dEbar = dE + (mean(ln det dF) - ln det dF) I/3. The material integrates dEbar in the
!> material axes of x_n from the stress of the last increment, in a frame that rotates
!> with the body. The material returns T, conjugate to dE per unit initial volume; the
!> second Piola-Kirchhoff stress relative to x_n is S = P^T T (P = d dE / d E_GL) and the
!> stress kept is the Kirchhoff stress dF S dF^T rotated back by dR of the polar
!> decomposition dF = dR dU, tau_hat = dU S dU, with the material axes turned by dR. The
!> update is objective (a rigid rotation leaves tau_hat unchanged) and keeps equilibrium
!> from one increment to the next (tau_hat gives back the converged forces). For coaxial
!> stretching tau_hat = T and logarithmic strains add, so uniaxial tension follows the
!> hardening law in Kirchhoff stress and logarithmic strain exactly; where dU and T are not
!> coaxial, tau_hat may stand off the yield surface by the order of |dE| |T|, and the next
!> increment returns it.
!> Voigt order 11, 22, 33, 12, 23, 31 with engineering shear strains throughout.
module ddpy_hex8
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_update_checked, material_check, material_yield_stress, &
                           material_prop_count, material_kinematic
  use ddpy_material_mixed, only: material_update_mixed
  use ddpy_element_products, only: lower_product, add_congruence, add_congruence_t
  use ddpy_log_strain, only: hencky_type, hencky_evaluate, hencky_first, hencky_second, &
                             hencky_stretch, tensor_from_stress, stress_from_tensor
  implicit none
  private
  public :: hex8_element, hex8_jacobians, hex8_stresses, pushed_stress

  !> Status values of hex8_element.
  integer, parameter, public :: hex8_ok = 0, hex8_inverted = 1, hex8_material_failed = 2

  !> Natural coordinates of the corners; the Gauss points are the corners / sqrt(3).
  real(wp), parameter :: corner(3, 8) = reshape([ &
    -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, &
    -1.0_wp, 1.0_wp, -1.0_wp, -1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, &
    1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp], [3, 8])
  real(wp), parameter :: gauss = 0.577350269189625764509148780502_wp

  real(wp), parameter :: identity_voigt(6) = [1.0_wp, 1.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]

contains

  !> Shape functions and their natural derivatives dn(a, j) = dN_a/dxi_j at xi.
  pure subroutine shape_functions(xi, n, dn)
    real(wp), intent(in) :: xi(3)
    real(wp), intent(out) :: n(8), dn(8, 3)
    real(wp) :: p(3)
    integer :: a
    do a = 1, 8
      p = 1.0_wp + corner(:, a)*xi
      n(a) = 0.125_wp*p(1)*p(2)*p(3)
      dn(a, 1) = 0.125_wp*corner(1, a)*p(2)*p(3)
      dn(a, 2) = 0.125_wp*corner(2, a)*p(1)*p(3)
      dn(a, 3) = 0.125_wp*corner(3, a)*p(1)*p(2)
    end do
  end subroutine shape_functions

  ! The small dense matrices: one source with the other element (see the file).
  include "ddpy_small_matrix.inc"

  !> Reference gradients g(a, J) = dN_a/dX_J and det J0 at natural point xi; g = 0 when
  !> det J0 <= 0.
  pure subroutine reference_gradients(x, xi, g, detj)
    real(wp), intent(in) :: x(3, 8), xi(3)
    real(wp), intent(out) :: g(8, 3), detj
    real(wp) :: n(8), dn(8, 3), jac(3, 3), inv(3, 3)
    call shape_functions(xi, n, dn)
    jac = matmul(x, dn)
    detj = det3(jac)
    if (detj <= 0.0_wp) then
      g = 0.0_wp
      return
    end if
    inv = inverse3(jac, 1.0_wp)
    g = matmul(dn, inv)/detj
  end subroutine reference_gradients

  !> det J0 of the reference element at the 8 Gauss points (1:8) and the 8 corners (9:16).
  pure subroutine hex8_jacobians(x, detj)
    real(wp), intent(in) :: x(3, 8)
    real(wp), intent(out) :: detj(16)
    real(wp) :: n(8), dn(8, 3)
    integer :: p
    do p = 1, 8
      call shape_functions(gauss*corner(:, p), n, dn)
      detj(p) = det3(matmul(x, dn))
      call shape_functions(corner(:, p), n, dn)
      detj(8 + p) = det3(matmul(x, dn))
    end do
  end subroutine hex8_jacobians

  !> Green-Lagrange strain (Voigt, engineering shears) of a deformation gradient.
  pure function green_lagrange(f) result(e)
    real(wp), intent(in) :: f(3, 3)
    real(wp) :: e(6)
    real(wp) :: c(3, 3)
    c = matmul(transpose(f), f)
    e = [0.5_wp*(c(1, 1) - 1.0_wp), 0.5_wp*(c(2, 2) - 1.0_wp), 0.5_wp*(c(3, 3) - 1.0_wp), &
         c(1, 2), c(2, 3), c(3, 1)]
  end function green_lagrange

  !> Internal force, tangent and trial material state of one element over an increment.
  !>
  !> x0: initial coordinates; xn: coordinates at the last converged increment (the
  !> reference of the increment); du: displacement increment from xn. State per Gauss point
  !> at xn: axes_old (material axes as columns), stress_old (tau_hat in material axes),
  !> ep_old, strain_old (accumulated logarithmic strain in material axes), back_old (the
  !> backstress in material axes, read only for mixed hardening).
  !> Out: f = sum W0 dEbar/du^T T, k = d f / d du (24 x 24, symmetric; only when
  !> want_tangent), the trial state (stress, ep, strain, axes, back: pushed forward and
  !> turned like the stress, back_old where there is no kinematic hardening) and status
  !> hex8_ok, hex8_inverted (det J or det dF <= 0 at a Gauss point) or
  !> hex8_material_failed. With mixed hardening the material's tangent enters by its
  !> symmetric part (the element's tangent is symmetric; docs/theory/material.md).
  pure subroutine hex8_element(x0, xn, du, props, axes_old, stress_old, ep_old, strain_old, &
                               back_old, want_tangent, f, k, stress, ep, strain, axes, back, &
                               status)
    real(wp), intent(in) :: x0(3, 8), xn(3, 8), du(3, 8), props(material_prop_count)
    real(wp), intent(in) :: axes_old(3, 3, 8), stress_old(6, 8), ep_old(8), strain_old(6, 8), &
                            back_old(6, 8)
    logical, intent(in) :: want_tangent
    real(wp), intent(out) :: f(24), k(24, 24), stress(6, 8), ep(8), strain(6, 8), &
                             axes(3, 3, 8), back(6, 8)
    integer, intent(out) :: status
    type(hencky_type) :: hk(8)
    ! bt(:, :, p) = b^T, the derivative of E_GL (Voigt) by the 24 dofs, stored by dof so that
    ! the products over the dofs are contiguous and vectorize; with rk, the 6 x 8 columns
    ! of the tangent k = bt rk^T + bbar_tr dv_sum^T (lower triangle).
    real(wp) :: g(8, 3, 8), w0(8), bt(24, 6, 8), btr(24, 8), lnj(8), pm(6, 6, 8), tg(6, 8), &
                trt(8), dg(6, 6, 8), rp(6, 6, 8), fgs(3, 3, 8), rk(24, 6, 8), dv_sum(24)
    real(wp) :: fg(3, 3), vj, vol, mean_lnj, bbar_tr(24), kg(8, 8), n8(8), dn8(8, 3), &
                rot(6, 6), de(6), s_mat(6), d_mat(6, 6), a_hat(6), mmat(6, 6), dm(6), &
                u(3, 3), u_inv(3, 3), ct, dmm, s6(6), s3(3, 3), &
                dtr(24), dv(24), yield_floor, x_mat(6), x6(6), xg(6)
    integer :: p, a, c, i, j, col, mstatus
    logical :: plastic, kinematic

    f = 0.0_wp
    stress = stress_old
    ep = ep_old
    strain = strain_old
    axes = axes_old
    back = back_old
    status = hex8_ok

    ! Pass 1: gradients on xn, relative deformation, both strains and the derivatives:
    ! dE_GL = b du, d dE = P b du, d ln det dF = m^T P b du = btr du (m = (1,1,1,0,0,0)).
    do p = 1, 8
      call shape_functions(gauss*corner(:, p), n8, dn8)
      w0(p) = det3(matmul(x0, dn8))
      call reference_gradients(xn, gauss*corner(:, p), g(:, :, p), vj)
      if (w0(p) <= 0.0_wp .or. vj <= 0.0_wp) then
        status = hex8_inverted
        k = 0.0_wp
        return
      end if
      fg = relative_gradient(du, g(:, :, p))
      if (det3(fg) <= 0.0_wp) then
        status = hex8_inverted
        k = 0.0_wp
        return
      end if
      fgs(:, :, p) = fg
      call hencky_evaluate(green_lagrange(fg), hk(p))
      lnj(p) = hk(p)%strain(1) + hk(p)%strain(2) + hk(p)%strain(3)
      do a = 1, 8
        do c = 1, 3
          col = 3*(a - 1) + c
          bt(col, 1, p) = fg(c, 1)*g(a, 1, p)
          bt(col, 2, p) = fg(c, 2)*g(a, 2, p)
          bt(col, 3, p) = fg(c, 3)*g(a, 3, p)
          bt(col, 4, p) = fg(c, 1)*g(a, 2, p) + fg(c, 2)*g(a, 1, p)
          bt(col, 5, p) = fg(c, 2)*g(a, 3, p) + fg(c, 3)*g(a, 2, p)
          bt(col, 6, p) = fg(c, 3)*g(a, 1, p) + fg(c, 1)*g(a, 3, p)
        end do
      end do
      call hencky_first(hk(p), pm(:, :, p))
      s6 = pm(1, :, p) + pm(2, :, p) + pm(3, :, p)
      btr(:, p) = by_dofs(bt(:, :, p), s6)
    end do

    ! Averages over the element of ln det dF and of its gradient, weighted by the initial
    ! volumes: the same weights in every increment, so that the stress kept gives back the
    ! converged forces exactly (weights of xn would shift the mean pressure between
    ! increments).
    vol = sum(w0)
    mean_lnj = dot_product(w0, lnj)/vol
    bbar_tr = 0.0_wp
    do p = 1, 8
      bbar_tr = bbar_tr + w0(p)*btr(:, p)
    end do
    bbar_tr = bbar_tr/vol

    ! Pass 2: mean-dilatation strain, material update in the axes of xn, force
    ! f = sum W0 Bbar^T T with Bbar = P b + m (bbar_tr - btr)^T/3, and the state rotated to
    ! the end of the increment. The properties are checked once for the 8 points.
    if (material_check(props) /= 0) then
      status = hex8_material_failed
      k = 0.0_wp
      return
    end if
    yield_floor = material_yield_stress(props, 0.0_wp)
    kinematic = material_kinematic(props)
    do p = 1, 8
      de = hk(p)%strain + (mean_lnj - lnj(p))/3.0_wp*identity_voigt
      call strain_map(axes_old(:, :, p), rot)
      de = matmul(rot, de)
      if (kinematic) then
        call material_update_mixed(props, yield_floor, stress_old(:, p), back_old(:, p), &
                                   ep_old(p), de, s_mat, x_mat, ep(p), d_mat, plastic, mstatus)
        d_mat = 0.5_wp*(d_mat + transpose(d_mat))
      else
        call material_update_checked(props, yield_floor, stress_old(:, p), ep_old(p), de, &
                                     s_mat, ep(p), d_mat, plastic, mstatus)
      end if
      if (mstatus > 0) then
        status = hex8_material_failed
        k = 0.0_wp
        return
      end if
      strain(:, p) = strain_old(:, p) + de
      do c = 1, 6
        tg(c, p) = dot_product(rot(:, c), s_mat)
      end do
      trt(p) = tg(1, p) + tg(2, p) + tg(3, p)
      if (want_tangent) then
        dg(:, :, p) = d_mat
        rp(:, :, p) = matmul(rot, pm(:, :, p))
      end if
      do c = 1, 6
        s6(c) = dot_product(tg(:, p), pm(:, c, p))
      end do
      f = f + w0(p)*(by_dofs(bt(:, :, p), s6) + (bbar_tr - btr(:, p))*trt(p)/3.0_wp)
      ! The stress at the end of the increment in the axes turned by dR = dF dU^-1: the
      ! rotated Kirchhoff stress dU S dU, S = P^T T relative to xn per unit initial volume.
      call hencky_stretch(hk(p), u, u_inv)
      axes(:, :, p) = product3(product3(fgs(:, :, p), u_inv), axes_old(:, :, p))
      if (kinematic) then
        ! The backstress by the stress's own map: to global axes, P^T, dU . dU, turned.
        do c = 1, 6
          xg(c) = dot_product(rot(:, c), x_mat)
        end do
        do c = 1, 6
          x6(c) = dot_product(xg, pm(:, c, p))
        end do
        back(:, p) = pushed_stress(u, x6, axes_old(:, :, p))
      end if
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
    if (.not. want_tangent) then
      k = 0.0_wp
      return
    end if

    ! Pass 3, the tangent. Material part W0 Bbar^T D Bbar expanded in b and the rank-one
    ! mean-dilatation terms; geometric part sum_p A_p : d2 dE_p with A_p = W0 T_p + a_p I,
    ! a_p moving the pressure to the element average, by the chain rule
    ! A : d2 dE = b^T L(A) b + (P^T A) : d2 E_GL (the last the familiar g S g^T). So
    ! K_p = b^T (W0 P^T D P + L(A)) b + W0/3 (v dtr^T + dtr v^T) + W0 m^T D m/9 dtr dtr^T,
    ! v = b^T P^T D m, dtr = bbar_tr - btr. With dv = v/3 + W0 m^T D m/9 dtr and
    ! btr = b^T P^T m, K_p = b^T R_p^T + bbar_tr dv^T, R_p^T = M b + (D m/3) dtr^T - P^T m dv^T:
    ! six columns of rk per Gauss point, and one product of rank 49 at the end.
    ct = dot_product(w0, trt)/3.0_wp
    kg = 0.0_wp
    dv_sum = 0.0_wp
    do p = 1, 8
      a_hat = w0(p)*tg(:, p) + (w0(p)/vol*ct - w0(p)*trt(p)/3.0_wp)*identity_voigt
      ! With R = rot P (material axes): P^T D_global P = R^T D R, and D_global m = rot^T D m
      ! since the identity strain m is the same in every axes.
      call hencky_second(hk(p), a_hat, mmat)
      call add_congruence(w0(p), rp(:, :, p), dg(:, :, p), mmat)
      s6 = dg(:, 1, p) + dg(:, 2, p) + dg(:, 3, p)
      do c = 1, 6
        dm(c) = w0(p)*dot_product(rp(:, c, p), s6)/3.0_wp
      end do
      dmm = w0(p)*sum(dg(1:3, 1:3, p))/9.0_wp
      dtr = bbar_tr - btr(:, p)
      dv = by_dofs(bt(:, :, p), dm) + dmm*dtr
      dv_sum = dv_sum + dv
      s6 = pm(1, :, p) + pm(2, :, p) + pm(3, :, p)
      do i = 1, 6
        rk(:, i, p) = by_dofs(bt(:, :, p), mmat(i, :)) + dm(i)*dtr - s6(i)*dv
      end do
      do c = 1, 6
        s6(c) = dot_product(a_hat, pm(:, c, p))
      end do
      call add_congruence_t(g(:, :, p), stress_tensor(s6), kg)
    end do
    call lower_product(bt, rk, bbar_tr, dv_sum, k)
    do j = 1, 8
      do i = j, 8
        do c = 1, 3
          k(3*(i - 1) + c, 3*(j - 1) + c) = k(3*(i - 1) + c, 3*(j - 1) + c) + kg(i, j)
        end do
      end do
    end do
    call mirror(k)
  end subroutine hex8_element

  !> The rotated Kirchhoff form dU S dU of a stress-like Voigt vector s6 (global axes),
  !> in the components of the material axes axes_old (which dR turns with the body): the
  !> map the elements apply to the stress at the end of an increment, for the backstress.
  pure function pushed_stress(u, s6, axes_old) result(v6)
    real(wp), intent(in) :: u(3, 3), s6(6), axes_old(3, 3)
    real(wp) :: v6(6)
    real(wp) :: t3(3, 3), s3(3, 3), w(3, 3)
    integer :: i, j
    t3 = product3(u, product3(stress_tensor(s6), u))
    s3 = product3(t3, axes_old)
    do j = 1, 3
      do i = 1, 3
        w(i, j) = dot_product(axes_old(:, i), s3(:, j))
      end do
    end do
    v6 = [w(1, 1), w(2, 2), w(3, 3), 0.5_wp*(w(1, 2) + w(2, 1)), 0.5_wp*(w(2, 3) + w(3, 2)), &
          0.5_wp*(w(3, 1) + w(1, 3))]
  end function pushed_stress

  !> dF = I + du g^T over the 8 nodes (g(a, :) the gradient of N_a).
  pure function relative_gradient(du, g) result(fg)
    real(wp), intent(in) :: du(3, 8), g(8, 3)
    real(wp) :: fg(3, 3)
    integer :: a, i, j
    do j = 1, 3
      do i = 1, 3
        fg(i, j) = merge(1.0_wp, 0.0_wp, i == j)
        do a = 1, 8
          fg(i, j) = fg(i, j) + du(i, a)*g(a, j)
        end do
      end do
    end do
  end function relative_gradient

  !> Copies the lower triangle of k to the upper.
  pure subroutine mirror(k)
    real(wp), intent(inout) :: k(24, 24)
    integer :: i, j
    do j = 2, 24
      do i = 1, j - 1
        k(i, j) = k(j, i)
      end do
    end do
  end subroutine mirror

  !> Stresses and positions at the 8 Gauss points from the state at total displacement u:
  !> Cauchy sigma = tau / det F and second Piola-Kirchhoff S = F^-1 tau F^-T (global axes),
  !> tau = Q tau_hat Q^T with Q the material axes. Status hex8_inverted when det J0 or
  !> det F <= 0.
  pure subroutine hex8_stresses(x0, u, axes, stress_mat, pk2, cauchy, points, status)
    real(wp), intent(in) :: x0(3, 8), u(3, 8), axes(3, 3, 8), stress_mat(6, 8)
    real(wp), intent(out) :: pk2(6, 8), cauchy(6, 8), points(3, 8)
    integer, intent(out) :: status
    real(wp) :: g(8, 3), detj, fg(3, 3), tau(3, 3), finv(3, 3), n(8), dn(8, 3), jf
    integer :: p, i
    status = hex8_ok
    pk2 = 0.0_wp
    cauchy = 0.0_wp
    do p = 1, 8
      call shape_functions(gauss*corner(:, p), n, dn)
      points(:, p) = matmul(x0 + u, n)
      call reference_gradients(x0, gauss*corner(:, p), g, detj)
      fg = matmul(u, g)
      do i = 1, 3
        fg(i, i) = fg(i, i) + 1.0_wp
      end do
      jf = det3(fg)
      if (detj <= 0.0_wp .or. jf <= 0.0_wp) then
        status = hex8_inverted
        cycle
      end if
      tau = matmul(axes(:, :, p), matmul(tensor_from_stress(stress_mat(:, p)), &
                                         transpose(axes(:, :, p))))
      cauchy(:, p) = stress_from_tensor(tau)/jf
      finv = inverse3(fg, jf)
      pk2(:, p) = stress_from_tensor(matmul(finv, matmul(tau, transpose(finv))))
    end do
  end subroutine hex8_stresses

end module ddpy_hex8
