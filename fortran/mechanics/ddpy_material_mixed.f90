!> Mixed isotropic-kinematic hardening of the blank: the return mapping of ddpy_material
!> (Hill'48, the isotropic law of props) on the stress relative to an Armstrong-Frederick
!> backstress with saturation (Lemaitre and Chaboche, as DD3IMP has it), its consistent
!> tangent (../docs/theory/material.md, "Mixed hardening"). A module of its own so that
!> the isotropic update of ddpy_material compiles as before, to the bit.
module ddpy_material_mixed
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count, material_hardening, hill48_equivalent_stress, &
                           yield_tol, &
                           return_tol, max_iterations, kinematic_rate, kinematic_saturation, &
                           material_ok, material_not_converged, material_bad_input, &
                           prop_young, prop_poisson, prop_hill
  implicit none
  private
  public :: material_update_mixed

  !> Voigt vector of ones on the normal components.
  real(wp), parameter :: unit_normal(6) = [1.0_wp, 1.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]

contains

  !> material_update_checked with mixed hardening (Lemaitre and Chaboche, as DD3IMP has
  !> it): Hill'48 on the relative stress eta = stress - back, the isotropic law of props
  !> for Y(ep), and the Armstrong-Frederick backstress with saturation,
  !> d back = C_X (X_sat eta'/sigma(eta) - back) d ep, sigma(eta) the Hill'48 equivalent
  !> stress (docs/theory/material.md). Backward Euler: with dep the one scalar unknown,
  !> back = (back_old + C_X X_sat dlambda eta')/(1 + C_X dep), dlambda = dep/Y, and every
  !> deviatoric mode of eta is a closed function of dep. back_old, back: the backstress
  !> (deviatoric, Voigt); tangent: d stress / d strain_increment, exact for the discrete
  !> update and not symmetric where back is not along eta.
  pure subroutine material_update_mixed(props, yield_floor, stress_old, back_old, ep_old, &
                                        strain_increment, stress, back, ep, tangent, &
                                        plastic, status)
    real(wp), intent(in) :: props(material_prop_count), yield_floor, stress_old(6), &
                            back_old(6), ep_old, strain_increment(6)
    real(wp), intent(out) :: stress(6), back(6), ep, tangent(6, 6)
    logical, intent(out) :: plastic
    integer, intent(out) :: status
    real(wp) :: shear, bulk, modes(6, 5), q(5), c(5), mu(5), trial(6), pressure, t(5), &
                xn(5), r(5), eta(5), xk(5), zz(5), v(5), m(5), u(5), diag(5)
    real(wp) :: sigma_trial, y_old, h, y, d, d_lo, d_hi, d_new, g, dg, b, cx, xsat, &
                sigma, dlambda, kappa, hdl, den
    integer :: iter, k
    logical :: converged

    plastic = .false.
    stress = stress_old
    back = back_old
    ep = ep_old
    call elastic_moduli(props, shear, bulk)
    tangent = elastic_tangent(shear, bulk)
    if (.not. (all(ieee_is_finite(stress_old)) .and. all(ieee_is_finite(strain_increment)) &
               .and. all(ieee_is_finite(back_old)) .and. ieee_is_finite(ep_old))) then
      status = material_bad_input
      return
    end if
    if (ep_old < 0.0_wp) then
      status = material_bad_input
      return
    end if
    status = material_ok

    trial = stress_old + matmul(tangent, strain_increment)
    sigma_trial = hill48_equivalent_stress(props(prop_hill:prop_hill + 5), trial - back_old)
    if (sigma_trial <= yield_floor*(1.0_wp + yield_tol)) then
      stress = trial
      return
    end if
    call material_hardening(props, ep_old, y_old, h)
    if (sigma_trial <= y_old*(1.0_wp + yield_tol)) then
      stress = trial
      return
    end if
    plastic = .true.
    cx = props(kinematic_rate)
    xsat = props(kinematic_saturation)
    call hill48_modes(props(prop_hill:prop_hill + 5), shear, modes, q, c, mu)
    t = matmul(trial, modes)
    xn = matmul(back_old, modes)
    pressure = sum(trial(1:3))/3.0_wp

    ! g(d) = 1/psi(d) - 1, psi the Hill norm of eta/Y at dep = d: g(0) < 0, and g(d_hi) >= 0
    ! since every denominator of psi exceeds Y(ep_old) + 2 G min(q) d and the numerator's
    ! Hill norm is at most sigma_trial + sigma(back_old).
    d_lo = 0.0_wp
    d_hi = (sigma_trial + hill48_equivalent_stress(props(prop_hill:prop_hill + 5), back_old) &
            - y_old)/(2.0_wp*shear*minval(q))
    d = 0.0_wp
    converged = .false.
    do iter = 1, max_iterations
      call residual_at(d, g, dg, r, y, h, b)
      if (abs(g) <= return_tol) then
        converged = .true.
        exit
      end if
      if (g < 0.0_wp) then
        d_lo = d
      else
        d_hi = d
      end if
      d_new = d - g/dg
      if (.not. (d_new > d_lo .and. d_new < d_hi)) d_new = 0.5_wp*(d_lo + d_hi)
      if (abs(d_new - d) <= 4.0_wp*epsilon(1.0_wp)*d .or. &
          d_hi - d_lo <= 4.0_wp*epsilon(1.0_wp)*d_hi) then
        d = d_new
        call residual_at(d, g, dg, r, y, h, b)
        converged = abs(g) <= 1.0e3_wp*return_tol
        exit
      end if
      d = d_new
    end do
    if (.not. converged) then
      plastic = .false.
      stress = stress_old
      status = material_not_converged
      return
    end if

    ! The converged state (r, y, h, b from the last residual_at, at d).
    eta = y*r
    sigma = sqrt(sum(c*eta*eta))
    dlambda = d/y
    xk = b*(xn + cx*xsat*dlambda*eta)
    stress = pressure*unit_normal + matmul(modes, eta + xk)
    back = matmul(modes, xk)
    ep = ep_old + d

    ! Consistent tangent on the deviatoric modes, D = diag + u v^T / den (the derivation in
    ! docs/theory/material.md); the pressure is elastic.
    kappa = b*cx*xsat
    hdl = h*dlambda
    zz = 1.0_wp + 2.0_wp*shear*dlambda*q + kappa*dlambda
    diag = mu*(1.0_wp + kappa*dlambda)/zz
    v = c*eta*mu/zz
    m = (1.0_wp - hdl)/sigma*(c + kappa/mu)*eta - cx*b*xk/mu
    den = h*sigma + sum(v*m)
    u = -(1.0_wp - hdl)/sigma*v - b*cx*2.0_wp*shear*dlambda*q*xk/zz
    tangent = 0.0_wp
    tangent(1:3, 1:3) = bulk
    do k = 1, 2
      tangent(1:3, 1:3) = tangent(1:3, 1:3) + diag(k)*outer(modes(1:3, k), modes(1:3, k))
    end do
    do k = 3, 5
      tangent(k + 1, k + 1) = diag(k)
    end do
    tangent = tangent + outer(matmul(modes, u), matmul(modes, v))/den
    if (.not. all(ieee_is_finite(tangent))) then
      plastic = .false.
      stress = stress_old
      back = back_old
      ep = ep_old
      tangent = elastic_tangent(shear, bulk)
      status = material_not_converged
    end if

  contains

    !> g = 1/psi - 1 at dep = dd and its derivative, with rr = eta/Y, yy = Y, hh = dY/dep
    !> and bb = 1/(1 + C_X dd) there.
    pure subroutine residual_at(dd, gg, dgg, rr, yy, hh, bb)
      real(wp), intent(in) :: dd
      real(wp), intent(out) :: gg, dgg, rr(5), yy, hh, bb
      real(wp) :: numer(5), denom(5), dr(5), psi
      bb = 1.0_wp/(1.0_wp + cx*dd)
      call material_hardening(props, ep_old + dd, yy, hh)
      numer = t - bb*xn
      denom = yy + dd*(2.0_wp*shear*q + cx*xsat*bb)
      rr = numer/denom
      dr = (cx*bb*bb*xn - rr*(hh + 2.0_wp*shear*q + cx*xsat*bb*bb))/denom
      psi = sqrt(sum(c*rr*rr))
      gg = 1.0_wp/psi - 1.0_wp
      dgg = -sum(c*rr*dr)/psi**3
    end subroutine residual_at

  end subroutine material_update_mixed

  ! elastic_moduli, elastic_tangent, hill48_modes and outer: one source with
  ! ddpy_material's (see the file).
  include "ddpy_material_helpers.inc"

end module ddpy_material_mixed
