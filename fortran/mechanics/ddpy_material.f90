!> Elastoplastic material of the blank: isotropic linear elasticity, Hill'48 yield function in
!> the material axes (1 = rolling, 2 = transverse, 3 = normal direction), Swift or Voce
!> isotropic hardening, associative flow, backward-Euler return mapping with the consistent
!> tangent (../docs/theory/material.md).
!>
!> Voigt order (11, 22, 33, 12, 23, 31); strains with engineering shears (gamma = 2 eps),
!> stresses plain, so that stress . strain is the work. The hydrostatic stress is elastic (the
!> Hill form does not see it), and on the five deviatoric modes that diagonalise the Hill form
!> against the isotropic compliance, (C^-1 + dlambda P)^-1 is diagonal: the stress is a closed
!> function of the one plastic multiplier, found by a bracketed Newton iteration.
module ddpy_material
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: material_update, material_update_checked, material_hardening, &
            material_yield_stress, material_check, hill48_from_r_values, hill48_is_convex, &
            hill48_equivalent_stress, yield_landing, material_kinematic

  !> Length of the property vector:
  !> (1) E, (2) nu, (3) F, (4) G, (5) H, (6) L, (7) M, (8) N, (9) hardening law
  !> (1 = Swift, 2 = Voce, 3 = table); Swift: (10) K, (11) eps0, (12) n; Voce: (10) Y0,
  !> (11) Q, (12) b; table: (10) the number of points n, then from (17) the points as pairs
  !> (ep_i, Y_i), i = 1..n, ep_1 = 0, ep increasing, Y non-decreasing, interpolated linearly,
  !> Y constant beyond the last point; (13) C_X and (14) X_sat of the Armstrong-Frederick
  !> backstress (mixed hardening when both are positive, see material_update_mixed);
  !> (15:16) and the unused rest reserved, zero.
  integer, parameter, public :: table_max_points = 100
  integer, parameter, public :: table_start = 16
  integer, parameter, public :: material_prop_count = table_start + 2*table_max_points
  !> Where the properties sit in props: Young's modulus, Poisson's ratio, Hill's F, G, H,
  !> L, M, N from prop_hill, the hardening law and its three parameters from
  !> prop_hardening.
  integer, parameter, public :: prop_young = 1, prop_poisson = 2, prop_hill = 3, &
                                prop_law = 9, prop_hardening = 10
  !> Where C_X and X_sat of the kinematic hardening sit in props.
  integer, parameter, public :: kinematic_rate = 13, kinematic_saturation = 14
  !> Hardening laws, props(prop_law).
  integer, parameter, public :: hardening_swift = 1, hardening_voce = 2, hardening_table = 3
  !> Status of material_update: converged; return mapping failed (the caller cuts the
  !> increment); properties invalid (see material_check); non-finite input.
  integer, parameter, public :: material_ok = 0, material_not_converged = 1, &
                                material_bad_props = 2, material_bad_input = 3

  !> Relative overstress below which a trial state counts as elastic.
  real(wp), parameter :: yield_tol = 1.0e-12_wp
  !> Relative tolerance on |Y(ep)/sigma_eq - 1| of the return mapping.
  real(wp), parameter :: return_tol = 1.0e-13_wp
  integer, parameter :: max_iterations = 200
  public :: yield_tol, return_tol, max_iterations

  !> Voigt vector of ones on the normal components, (1, 1, 1, 0, 0, 0).
  real(wp), parameter :: unit_normal(6) = [1.0_wp, 1.0_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]

contains

  !> Backward-Euler update of one material point over a strain increment.
  !> stress_old, ep_old: converged state; strain_increment: (engineering shears) increment.
  !> stress, ep: updated state; tangent(i, j) = d stress(i) / d strain_increment(j), the
  !> consistent tangent (symmetric); plastic: the point yielded in this increment;
  !> status: material_ok (0) or > 0 when no update is returned (stress = stress_old,
  !> ep = ep_old, elastic tangent or zero for invalid properties).
  pure subroutine material_update(props, stress_old, ep_old, strain_increment, stress, ep, &
                                  tangent, plastic, status)
    real(wp), intent(in) :: props(material_prop_count), stress_old(6), ep_old, &
                            strain_increment(6)
    real(wp), intent(out) :: stress(6), ep, tangent(6, 6)
    logical, intent(out) :: plastic
    integer, intent(out) :: status
    if (material_check(props) /= 0) then
      plastic = .false.
      stress = stress_old
      ep = ep_old
      tangent = 0.0_wp
      status = material_bad_props
      return
    end if
    call material_update_checked(props, material_yield_stress(props, 0.0_wp), stress_old, &
                                 ep_old, strain_increment, stress, ep, tangent, plastic, status)
  end subroutine material_update

  !> material_update for properties that passed material_check, with yield_floor =
  !> material_yield_stress(props, 0), the smallest yield stress (both laws are
  !> non-decreasing for valid properties): for the many points of an element assembly,
  !> which check the properties once, and whose trial stress below the floor is elastic
  !> without evaluating the hardening law (a pow for Swift).
  pure subroutine material_update_checked(props, yield_floor, stress_old, ep_old, &
                                          strain_increment, stress, ep, tangent, plastic, &
                                          status)
    real(wp), intent(in) :: props(material_prop_count), yield_floor, stress_old(6), ep_old, &
                            strain_increment(6)
    real(wp), intent(out) :: stress(6), ep, tangent(6, 6)
    logical, intent(out) :: plastic
    integer, intent(out) :: status
    real(wp) :: shear, bulk, modes(6, 5), q(5), c(5), mu(5), a(5), w(5), trial(6)
    real(wp) :: pressure, sigma_trial, y_old, h, x, x_lo, x_hi, x_new, sigma, dsigma, y
    real(wp) :: g, dg, dlambda, hdl, xi_n(6), beta
    integer :: iter, k
    logical :: converged

    plastic = .false.
    stress = stress_old
    ep = ep_old
    call elastic_moduli(props, shear, bulk)
    tangent = elastic_tangent(shear, bulk)
    if (.not. (all(ieee_is_finite(stress_old)) .and. all(ieee_is_finite(strain_increment)) &
               .and. ieee_is_finite(ep_old))) then
      status = material_bad_input
      return
    end if
    if (ep_old < 0.0_wp) then
      status = material_bad_input
      return
    end if
    status = material_ok

    trial = stress_old + matmul(tangent, strain_increment)
    sigma_trial = hill48_equivalent_stress(props(prop_hill:prop_hill + 5), trial)
    ! Y(ep_old) >= yield_floor: below the floor the test below is passed whatever Y is.
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
    call hill48_modes(props(prop_hill:prop_hill + 5), shear, modes, q, c, mu)
    a = matmul(trial, modes)
    pressure = sum(trial(1:3))/3.0_wp

    ! g(x) = Y(ep(x))/sigma(x) - 1 rises from g(0) < 0; x = 2 shear dlambda is dimensionless.
    ! Since sigma(x) <= sigma_trial/(1 + x min(q)) and Y >= y_old, g(x_hi) >= 0.
    x_lo = 0.0_wp
    x_hi = (sigma_trial/y_old - 1.0_wp)/minval(q)
    x = 0.0_wp
    converged = .false.
    do iter = 1, max_iterations
      call state_at(x, sigma, dsigma, y, h, g, dg)
      if (abs(g) <= return_tol) then
        converged = .true.
        exit
      end if
      if (g < 0.0_wp) then
        x_lo = x
      else
        x_hi = x
      end if
      x_new = x - g/dg
      ! Safeguard: bisect when Newton leaves the bracket (or dg is not usable).
      if (.not. (x_new > x_lo .and. x_new < x_hi)) x_new = 0.5_wp*(x_lo + x_hi)
      if (abs(x_new - x) <= 4.0_wp*epsilon(1.0_wp)*x .or. &
          x_hi - x_lo <= 4.0_wp*epsilon(1.0_wp)*x_hi) then
        ! Round-off level: the iterate cannot move any more.
        x = x_new
        call state_at(x, sigma, dsigma, y, h, g, dg)
        converged = abs(g) <= 1.0e3_wp*return_tol
        exit
      end if
      x = x_new
    end do
    if (.not. converged) then
      plastic = .false.
      stress = stress_old
      status = material_not_converged
      return
    end if

    ! Converged state: s = p m + sum_k w_k V_k, ep = ep_old + dlambda sigma_eq.
    w = a/(1.0_wp + x*q)
    stress = pressure*unit_normal + matmul(modes, w)
    dlambda = x/(2.0_wp*shear)
    ep = ep_old + dlambda*sigma

    ! Consistent tangent: D = Xi - beta (Xi n)(Xi n)^T, Xi = (C^-1 + dlambda P)^-1,
    ! n = P s, beta = (1 - H dlambda)/(H sigma^2 + (1 - H dlambda) n.Xi.n).
    hdl = h*dlambda
    xi_n = matmul(modes, mu*c*w/(1.0_wp + x*q))
    beta = (1.0_wp - hdl)/(h*sigma*sigma + (1.0_wp - hdl)*sum(mu*(c*w)**2/(1.0_wp + x*q)))
    tangent = 0.0_wp
    tangent(1:3, 1:3) = bulk
    do k = 1, 2
      tangent(1:3, 1:3) = tangent(1:3, 1:3) &
                          + mu(k)/(1.0_wp + x*q(k))*outer(modes(1:3, k), modes(1:3, k))
    end do
    do k = 3, 5
      tangent(k + 1, k + 1) = mu(k)/(1.0_wp + x*q(k))
    end do
    tangent = tangent - beta*outer(xi_n, xi_n)
    if (.not. all(ieee_is_finite(tangent))) then
      plastic = .false.
      stress = stress_old
      ep = ep_old
      tangent = elastic_tangent(shear, bulk)
      status = material_not_converged
    end if

  contains

    !> Equivalent stress and residual g = Y/sigma - 1 at x, with their x-derivatives.
    pure subroutine state_at(xx, sig, dsig, yy, hh, gg, dgg)
      real(wp), intent(in) :: xx
      real(wp), intent(out) :: sig, dsig, yy, hh, gg, dgg
      real(wp) :: ww(5), dep
      ww = a/(1.0_wp + xx*q)
      sig = sqrt(sum(c*ww*ww))
      dsig = -sum(c*q*ww*ww/(1.0_wp + xx*q))/sig
      call material_hardening(props, ep_old + xx*sig/(2.0_wp*shear), yy, hh)
      dep = (sig + xx*dsig)/(2.0_wp*shear)
      gg = yy/sig - 1.0_wp
      dgg = (hh*dep*sig - yy*dsig)/(sig*sig)
    end subroutine state_at

  end subroutine material_update_checked

  !> Yield stress Y(ep) and hardening slope dY/dep of the law in props(prop_law) and its
  !> parameters.
  pure subroutine material_hardening(props, ep, y, slope)
    real(wp), intent(in) :: props(material_prop_count), ep
    real(wp), intent(out) :: y, slope
    real(wp) :: base, decay
    select case (nint(props(prop_law)))
    case (hardening_swift)
      base = props(prop_hardening + 1) + max(ep, 0.0_wp)
      y = props(prop_hardening)*base**props(prop_hardening + 2)
      slope = props(prop_hardening + 2)*y/base
    case (hardening_voce)
      decay = exp(-props(prop_hardening + 2)*max(ep, 0.0_wp))
      y = props(prop_hardening) + props(prop_hardening + 1)*(1.0_wp - decay)
      slope = props(prop_hardening + 1)*props(prop_hardening + 2)*decay
    case (hardening_table)
      call table_hardening(props, ep, y, slope)
    case default
      y = 0.0_wp
      slope = 0.0_wp
    end select
  end subroutine material_hardening

  !> Piecewise-linear hardening of the table in props: Y(ep) interpolated between the points,
  !> the slope of the segment holding ep (the one to the right at a point), Y constant with a
  !> zero slope beyond the last point.
  pure subroutine table_hardening(props, ep, y, slope)
    real(wp), intent(in) :: props(material_prop_count), ep
    real(wp), intent(out) :: y, slope
    integer :: n, i
    real(wp) :: e, e0, e1, y0, y1
    n = nint(props(prop_hardening))
    e = max(ep, 0.0_wp)
    y = props(table_start + 2*n)
    slope = 0.0_wp
    do i = 1, n - 1
      e1 = props(table_start + 2*i + 1)
      if (e < e1) then
        e0 = props(table_start + 2*i - 1)
        y0 = props(table_start + 2*i)
        y1 = props(table_start + 2*i + 2)
        slope = (y1 - y0)/(e1 - e0)
        y = y0 + slope*(e - e0)
        return
      end if
    end do
  end subroutine table_hardening

  !> Yield stress Y(ep) (the RD uniaxial yield stress, since G + H = 1).
  pure function material_yield_stress(props, ep) result(y)
    real(wp), intent(in) :: props(material_prop_count), ep
    real(wp) :: y, slope
    call material_hardening(props, ep, y, slope)
  end function material_yield_stress

  !> 0 when the properties are valid, else the 1-based index of the first bad one:
  !> 1 E <= 0, 2 nu outside (-1, 1/2), 3 Hill form (F, G, H) not positive definite on the
  !> deviator, 6/7/8 L/M/N <= 0, 9 unknown law, 10-12 bad hardening parameters
  !> (Swift: K > 0, eps0 > 0, 0 <= n <= 1; Voce: Y0 > 0, Q >= 0, b >= 0), or the index of a
  !> non-finite entry.
  pure function material_check(props) result(info)
    real(wp), intent(in) :: props(material_prop_count)
    integer :: info
    integer :: i
    info = 0
    do i = 1, material_prop_count
      if (.not. ieee_is_finite(props(i))) then
        info = i
        return
      end if
    end do
    if (props(prop_young) <= 0.0_wp) then
      info = prop_young
    else if (props(prop_poisson) <= -1.0_wp .or. props(prop_poisson) >= 0.5_wp) then
      info = prop_poisson
    else if (.not. hill48_is_convex(props(prop_hill:prop_hill + 5))) then
      info = prop_hill
      do i = prop_hill + 3, prop_hill + 5
        if (props(i) <= 0.0_wp) info = i
      end do
    else
      select case (nint(props(prop_law)))
      case (hardening_swift)
        if (props(prop_hardening) <= 0.0_wp) then
          info = prop_hardening
        else if (props(prop_hardening + 1) <= 0.0_wp) then
          info = prop_hardening + 1
        else if (props(prop_hardening + 2) < 0.0_wp .or. props(prop_hardening + 2) > 1.0_wp) then
          info = prop_hardening + 2
        end if
      case (hardening_voce)
        if (props(prop_hardening) <= 0.0_wp) then
          info = prop_hardening
        else if (props(prop_hardening + 1) < 0.0_wp) then
          info = prop_hardening + 1
        else if (props(prop_hardening + 2) < 0.0_wp) then
          info = prop_hardening + 2
        end if
      case (hardening_table)
        info = table_check(props)
      case default
        info = prop_law
      end select
    end if
    ! The backstress's Hill norm stays below X_sat; below the initial yield stress too, the
    ! stress-free state stays inside the yield surface (docs/theory/material.md).
    if (info == 0) then
      if (props(kinematic_rate) < 0.0_wp) then
        info = kinematic_rate
      else if (props(kinematic_saturation) < 0.0_wp .or. &
               props(kinematic_saturation) >= material_yield_stress(props, 0.0_wp)) then
        info = kinematic_saturation
      end if
    end if
  end function material_check

  !> The properties ask for mixed hardening: an Armstrong-Frederick backstress with
  !> C_X > 0 and X_sat > 0 (with either zero the backstress stays zero).
  pure logical function material_kinematic(props)
    real(wp), intent(in) :: props(material_prop_count)
    material_kinematic = props(kinematic_rate) > 0.0_wp .and. &
                         props(kinematic_saturation) > 0.0_wp
  end function material_kinematic

  !> 0 for a valid hardening table in props, else the 1-based index of the first bad entry:
  !> 10 a count outside 1..table_max_points, the first strain when not 0, a strain not above
  !> the one before, a yield stress not positive or below the one before.
  pure function table_check(props) result(info)
    real(wp), intent(in) :: props(material_prop_count)
    integer :: info
    integer :: n, i, at
    info = 0
    if (props(prop_hardening) < 1.0_wp .or. props(prop_hardening) > real(table_max_points, wp) .or. &
        props(prop_hardening) /= real(nint(props(prop_hardening)), wp)) then
      info = prop_hardening
      return
    end if
    n = nint(props(prop_hardening))
    if (props(table_start + 1) /= 0.0_wp) then
      info = table_start + 1
      return
    end if
    do i = 1, n
      at = table_start + 2*i
      if (props(at) <= 0.0_wp) then
        info = at
        return
      end if
      if (i > 1) then
        if (props(at - 1) <= props(at - 3)) then
          info = at - 1
          return
        end if
        if (props(at) < props(at - 2)) then
          info = at
          return
        end if
      end if
    end do
  end function table_check

  !> Hill'48 coefficients (F, G, H, L, M, N) from the r-values at 0, 45 and 90 degrees to the
  !> rolling direction, normalised to G + H = 1, with L = M = 1.5 (isotropic through the
  !> thickness). Non-positive r-values give all zeros (not a convex yield function).
  pure subroutine hill48_from_r_values(r0, r45, r90, coefficients)
    real(wp), intent(in) :: r0, r45, r90
    real(wp), intent(out) :: coefficients(6)
    coefficients = 0.0_wp
    if (.not. (r0 > 0.0_wp .and. r45 > 0.0_wp .and. r90 > 0.0_wp)) return
    coefficients(2) = 1.0_wp/(1.0_wp + r0)
    coefficients(3) = r0/(1.0_wp + r0)
    coefficients(1) = r0/(r90*(1.0_wp + r0))
    coefficients(4:5) = 1.5_wp
    coefficients(6) = (r0 + r90)*(1.0_wp + 2.0_wp*r45)/(2.0_wp*r90*(1.0_wp + r0))
  end subroutine hill48_from_r_values

  !> The Hill'48 quadratic form with coefficients (F, G, H, L, M, N) is positive definite on
  !> the deviatoric stresses (a convex, bounded yield surface).
  pure function hill48_is_convex(coefficients) result(ok)
    real(wp), intent(in) :: coefficients(6)
    logical :: ok
    associate (f => coefficients(1), g => coefficients(2), h => coefficients(3))
      ok = f + g > 0.0_wp .and. g + h > 0.0_wp .and. h + f > 0.0_wp &
           .and. f*g + g*h + h*f > 0.0_wp .and. all(coefficients(4:6) > 0.0_wp)
    end associate
  end function hill48_is_convex

  !> Hill'48 equivalent stress sqrt(2 f) of a Voigt stress (11, 22, 33, 12, 23, 31).
  pure function hill48_equivalent_stress(coefficients, stress) result(sigma)
    real(wp), intent(in) :: coefficients(6), stress(6)
    real(wp) :: sigma
    sigma = sqrt(max(0.0_wp, coefficients(1)*(stress(2) - stress(3))**2 &
                 + coefficients(2)*(stress(3) - stress(1))**2 &
                 + coefficients(3)*(stress(1) - stress(2))**2 &
                 + 2.0_wp*(coefficients(4)*stress(5)**2 + coefficients(5)*stress(6)**2 &
                           + coefficients(6)*stress(4)**2)))
  end function hill48_equivalent_stress

  !> The fraction of a strain increment at which the first material point that has not
  !> yielded yet (ep_old = 0) reaches the yield surface, if its elastic trial stress
  !> overshoots it by more than tolerance (a fraction of the yield stress); 1 otherwise. A
  !> point within tolerance below the surface counts as yielding already: landing it again
  !> would cut the increment to almost nothing, over and over. A point that has yielded
  !> before and unloaded is not landed when it reloads: on faceted tools every facet edge
  !> a point slides over unloads and reloads it, and landing each reloading multiplied the
  !> increments by five (docs/theory/contact.md, increment control). The Hill form is
  !> quadratic, so along the elastic path stress_old + s C de the landing s solves a
  !> quadratic; the fraction returned is the smallest s times 1 + tolerance / 2 (just past
  !> the surface), within [1e-6, 1].
  pure function yield_landing(props, k, stress_old, ep_old, strain_increment, tolerance) &
    result(fraction)
    real(wp), intent(in) :: props(material_prop_count), stress_old(6, k), ep_old(k), &
                            strain_increment(6, k), tolerance
    integer, intent(in) :: k
    real(wp) :: fraction, lam, shear, ds(6), y, qa, qab, qb, disc, s, smallest
    integer :: i
    lam = props(prop_young)*props(prop_poisson)/ &
          ((1.0_wp + props(prop_poisson))*(1.0_wp - 2.0_wp*props(prop_poisson)))
    shear = props(prop_young)/(2.0_wp*(1.0_wp + props(prop_poisson)))
    smallest = huge(1.0_wp)
    do i = 1, k
      if (ep_old(i) > 0.0_wp) cycle  ! yielded before: a reloading, not landed
      associate (a => stress_old(:, i), de => strain_increment(:, i))
        ds(1:3) = lam*(de(1) + de(2) + de(3)) + 2.0_wp*shear*de(1:3)
        ds(4:6) = shear*de(4:6)
        y = material_yield_stress(props, ep_old(i))
        qa = hill48_form(props(prop_hill:prop_hill + 5), a, a)
        if (.not. qa < (y*(1.0_wp - tolerance))**2) cycle  ! yielding already
        qab = hill48_form(props(prop_hill:prop_hill + 5), a, ds)
        qb = hill48_form(props(prop_hill:prop_hill + 5), ds, ds)
        if (.not. (qa + 2.0_wp*qab + qb > (y*(1.0_wp + tolerance))**2 .and. qb > 0.0_wp)) &
          cycle
        disc = max(qab**2 - qb*(qa - y**2), 0.0_wp)
        s = (-qab + sqrt(disc))/qb
        smallest = min(smallest, s)
      end associate
    end do
    fraction = 1.0_wp
    if (smallest < huge(1.0_wp)) &
      fraction = min(max(smallest*(1.0_wp + tolerance/2.0_wp), 1.0e-6_wp), 1.0_wp)
  end function yield_landing

  !> The symmetric bilinear form of twice the Hill'48 function, 2 f(sigma), of two Voigt
  !> vectors (11, 22, 33, 12, 23, 31): coefficients (F, G, H, L, M, N).
  pure function hill48_form(coefficients, a, b) result(q)
    real(wp), intent(in) :: coefficients(6), a(6), b(6)
    real(wp) :: q
    q = coefficients(1)*(a(2) - a(3))*(b(2) - b(3)) &
        + coefficients(2)*(a(3) - a(1))*(b(3) - b(1)) &
        + coefficients(3)*(a(1) - a(2))*(b(1) - b(2)) &
        + 2.0_wp*(coefficients(6)*a(4)*b(4) + coefficients(4)*a(5)*b(5) &
                  + coefficients(5)*a(6)*b(6))
  end function hill48_form

  include "ddpy_material_helpers.inc"

end module ddpy_material
